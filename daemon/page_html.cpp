#include "daemon/page_html.hpp"

namespace springscan::daemon {

namespace {

// Read from across the press line: the verdict is the largest thing on the screen, the state
// next; colours say PASS (green), FAIL (red), NO RESULT (amber). Ids are what the script and
// docs/operator-page.md name.
constexpr const char* kPage = R"PAGE(<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8">
<meta name="viewport" content="width=device-width, initial-scale=1">
<title>springscan station</title>
<style>
body{margin:0;font:16px/1.35 system-ui,sans-serif;background:#f2f3f5;color:#1b1d21}
header{display:flex;gap:1em;align-items:center;padding:.6em 1em;background:#1b1d21;color:#fff}
header h1{font-size:1.2em;margin:0;font-weight:600}
#conn{margin-left:auto;font-size:.85em;opacity:.8}
main{display:grid;grid-template-columns:minmax(320px,1fr) minmax(320px,1fr);gap:1em;padding:1em}
section{background:#fff;border-radius:6px;padding:.8em 1em;box-shadow:0 1px 2px #0002}
h2{font-size:1em;margin:.1em 0 .6em;text-transform:uppercase;letter-spacing:.05em;color:#555}
.state{display:inline-block;font-size:1.6em;font-weight:700;padding:.15em .6em;border-radius:4px;
 background:#dde;text-transform:uppercase}
.state.scanning,.state.analysing{background:#cfe3ff}.state.fault{background:#c62828;color:#fff}
.state.done,.state.idle{background:#e4e7eb}
#fault{color:#c62828;font-weight:600;margin:.5em 0 0}
.flags span{display:inline-block;margin:.4em .4em 0 0;padding:.1em .5em;border-radius:3px;
 background:#ffe08a}
#verdict{font-size:5em;font-weight:800;line-height:1;letter-spacing:.04em;margin:.1em 0}
#verdict.pass{color:#1b7f3b}#verdict.fail{color:#c62828}#verdict.none{color:#b26a00}
#verdict.undecided{color:#8a4fbf}
#last-meta{color:#555}
#reasons{margin:.4em 0;padding-left:1.2em;color:#c62828;font-weight:600}
table{border-collapse:collapse;width:100%;font-variant-numeric:tabular-nums}
th,td{text-align:right;padding:.25em .5em;border-bottom:1px solid #e3e5e8}
th:first-child,td:first-child{text-align:left}
tr.bad td{color:#c62828;font-weight:600}tr.undecided td{color:#8a4fbf;font-weight:600}
#map{width:100%;height:auto;max-height:420px;object-fit:contain;background:#fff}
.legend{font-size:.85em;color:#555}
.wide{grid-column:1/-1}
.counts{display:flex;gap:2em;flex-wrap:wrap}.counts div{font-size:.9em;color:#555}
.counts b{display:block;font-size:1.8em;color:#1b1d21}
#recent td.pass{color:#1b7f3b;font-weight:700}#recent td.fail{color:#c62828;font-weight:700}
#recent td.none{color:#b26a00;font-weight:700}#recent td.undecided{color:#8a4fbf;font-weight:700}#recent th,#recent td{text-align:left}
</style></head>
<body>
<header><h1>springscan <span id="station"></span></h1><span id="conn">connecting…</span></header>
<main>
<section><h2>Station</h2><div id="state" class="state">…</div><p id="fault" hidden></p>
<div class="flags" id="flags"></div></section>
<section><h2>Counts of the shift <span id="shift-start"></span></h2><div class="counts">
<div><b id="count-parts">0</b>parts</div><div><b id="count-pass">0</b>pass</div>
<div><b id="count-fail">0</b>fail</div><div><b id="count-undecided">0</b>undecided</div>
<div><b id="count-none">0</b>no result</div>
<div><b id="yield">–</b>yield</div></div></section>
<section><h2>Last part</h2><div id="verdict" class="none">–</div><div id="last-meta">no result
yet</div><div id="criteria"></div><ul id="reasons"></ul>
<p><a id="report-link" hidden>Open the full report</a></p></section>
<section><h2>Deviation colour map</h2><img id="map" alt="deviation colour map of the last part"
hidden><p class="legend" id="legend"></p></section>
<section class="wide"><h2>Bends</h2><table><thead><tr><th>Bend</th><th>Nominal °</th>
<th>Measured °</th><th>Springback °</th><th>U ± °</th><th>Tolerance ± °</th><th>Result</th></tr>
</thead>
<tbody id="bends"></tbody></table></section>
<section class="wide"><h2>Last results</h2><table id="recent"><thead><tr><th>Seq</th>
<th>Time</th><th>Job</th><th>Part</th><th>Verdict</th><th>Report</th></tr></thead>
<tbody></tbody></table></section>
</main>
<script>
'use strict';
const $ = (id) => document.getElementById(id);
const STATES = {starting: 'Starting', idle: 'Idle', scanning: 'Scanning', analysing: 'Analysing',
  done: 'Idle – result ready', fault: 'Fault'};
const VERDICT_CLASS = {PASS: 'pass', FAIL: 'fail', UNDECIDED: 'undecided'};
const BEND_RESULT = {CONFORMING: 'OK', NONCONFORMING: 'OUT', UNDECIDED: 'UNDECIDED'};
const num = (v, d) => (typeof v === 'number' && isFinite(v)) ? v.toFixed(d) : 'n/a';
function cell(tr, content, cls) {
  const td = document.createElement('td');
  if (content instanceof Node) td.appendChild(content); else td.textContent = content;
  if (cls) td.className = cls;
  tr.appendChild(td);
}
function link(href, label) {
  const a = document.createElement('a');
  a.href = href; a.textContent = label;
  return a;
}
function renderState(s) {
  $('station').textContent = s.station;
  const st = $('state');
  st.textContent = STATES[s.state] || s.state;
  st.className = 'state ' + s.state;
  $('fault').textContent = s.fault;
  $('fault').hidden = !s.fault;
  const flags = [];
  if (!s.scanner_online) flags.push('scanner offline');
  if (s.plc_comm_lost) flags.push('PLC communication lost');
  if (s.calibration_drift) flags.push('CALIBRATION DRIFT: the check part is beyond its references, recalibrate the heads');
  if (!s.ready && s.state === 'idle') flags.push('not ready');
  $('flags').replaceChildren(...flags.map((f) => {
    const span = document.createElement('span'); span.textContent = f; return span; }));
}
function renderLast(last) {
  const v = $('verdict');
  if (!last) return;
  v.textContent = last.verdict;
  v.className = VERDICT_CLASS[last.verdict] || 'none';
  v.dataset.record = last.record;
  v.dataset.seq = last.seq;
  $('last-meta').textContent = 'Result ' + last.seq + ' · job ' + last.job_id + ' · part ' +
      last.part_id + ' · ' + last.time + ' · cycle ' + num(last.cycle_time_ms / 1000, 1) + ' s';
  // UNDECIDED: a value lies within its uncertainty U of its limit (docs/operator-page.md).
  $('criteria').textContent = last.verdict === 'PASS' ? 'All criteria met.' :
      last.verdict === 'UNDECIDED' ?
      'Cannot tell: within the measurement uncertainty of a limit. Re-measure once, then ' +
      'check by hand:' : (last.reasons.length ? 'Failed criteria:' : '');
  // The reasons are the failed criteria; a part that passed has none to show.
  const failed = last.verdict === 'PASS' ? [] : last.reasons;
  $('reasons').replaceChildren(...failed.map((r) => {
    const li = document.createElement('li'); li.textContent = r; return li; }));
  const a = $('report-link');
  a.href = last.report; a.hidden = false;
  const map = $('map');
  if (last.picture) {
    if (map.getAttribute('src') !== last.picture) map.src = last.picture;
    map.hidden = false;
    const d = last.deviation;
    $('legend').textContent = 'Green: within ±' + num(d.tolerance_mm, 2) + ' mm of the CAD; ' +
        'blue below, red above (full colour at ±' + num(d.color_scale_mm, 2) + ' mm). rms ' +
        num(d.rms_mm, 3) + ' mm, p95 ' + num(d.p95_mm, 3) + ' mm' +
        (d.uncertainty_mm > 0 ? ' (U ±' + num(d.uncertainty_mm, 3) + ' mm)' : '') + '.';
  } else {
    map.hidden = true; map.removeAttribute('src');
    $('legend').textContent = 'No deviation map: the part was not measured.';
  }
  $('bends').replaceChildren(...last.bends.map((b) => {
    const tr = document.createElement('tr');
    const undecided = b.decision === 'UNDECIDED';
    if (!b.pass) tr.className = undecided ? 'undecided' : 'bad';
    cell(tr, 'B' + b.id);
    cell(tr, num(b.nominal_deg, 2));
    cell(tr, b.measured ? num(b.measured_deg, 2) : 'n/a');
    cell(tr, b.measured ? num(b.springback_deg, 2) : 'n/a');
    cell(tr, b.measured ? num(b.springback_uncertainty_deg, 3) : 'n/a');
    cell(tr, num(b.tolerance_deg, 2));
    cell(tr, !b.measured ? 'not measured' + (undecided ? ' (UNDECIDED)' : '') :
        (BEND_RESULT[b.decision] || (b.pass ? 'OK' : 'OUT')));
    return tr;
  }));
}
function renderRecent(recent) {
  $('recent').tBodies[0].replaceChildren(...recent.map((r) => {
    const tr = document.createElement('tr');
    tr.dataset.record = r.record;
    cell(tr, String(r.seq)); cell(tr, r.time); cell(tr, String(r.job_id)); cell(tr, r.part_id);
    cell(tr, r.verdict, VERDICT_CLASS[r.verdict] || 'none');
    cell(tr, link(r.report, 'report'));
    return tr;
  }));
}
function renderShift(shift) {
  $('shift-start').textContent = shift.start ? '(since ' + shift.start + ')' : '';
  $('count-parts').textContent = shift.parts;
  $('count-pass').textContent = shift.pass;
  $('count-fail').textContent = shift.fail;
  $('count-undecided').textContent = shift.undecided;
  $('count-none').textContent = shift.no_result;
  $('yield').textContent = shift.yield_pct === undefined ? '–' : num(shift.yield_pct, 1) + ' %';
}
function render(s) {
  renderState(s); renderLast(s.last); renderRecent(s.recent); renderShift(s.shift);
}
// The server pushes every change; the browser reconnects by itself (retry: 2 s).
const events = new EventSource('events');
events.addEventListener('station', (e) => { render(JSON.parse(e.data)); });
events.onopen = () => { $('conn').textContent = 'live'; };
events.onerror = () => { $('conn').textContent = 'connection lost – reconnecting…'; };
</script>
</body></html>
)PAGE";

}  // namespace

const char* operator_page_html() { return kPage; }

}  // namespace springscan::daemon
