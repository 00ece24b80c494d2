#include "report/report_style.hpp"

namespace springscan::report {

const char* report_css() {
  return R"css(
@page { size: A4; margin: 12mm 11mm 14mm 11mm; }
:root { --ink: #1c2330; --muted: #5b6576; --rule: #d5dae2; --pass: #18794e; --fail: #c0262d;
        --nm: #8a919c; --ud: #6f42a8; --band: #f3f5f8; }
* { box-sizing: border-box; }
html { font-family: "DejaVu Sans", "Liberation Sans", Arial, Helvetica, sans-serif;
       font-size: 13px; color: var(--ink); background: #fff; }
body { margin: 0 auto; max-width: 1160px; padding: 18px 22px 40px; }
h1 { font-size: 21px; margin: 0; font-weight: 600; letter-spacing: .2px; }
h2 { font-size: 15px; margin: 22px 0 8px; padding-bottom: 4px; border-bottom: 2px solid var(--ink);
     text-transform: uppercase; letter-spacing: .6px; break-after: avoid; page-break-after: avoid; }
header.top { display: flex; justify-content: space-between; align-items: flex-end;
             border-bottom: 1px solid var(--rule); padding-bottom: 8px; }
header.top .sub { color: var(--muted); font-size: 12px; margin-top: 3px; }
header.top .meta { text-align: right; color: var(--muted); font-size: 12px; line-height: 1.5; }
.banner { margin: 14px 0 6px; padding: 12px 18px; border-radius: 4px; color: #fff;
          display: flex; align-items: center; gap: 22px;
          -webkit-print-color-adjust: exact; print-color-adjust: exact; }
.banner.pass { background: var(--pass); }
.banner.fail { background: var(--fail); }
.banner.undecided { background: var(--ud); }
.banner .rule { font-size: 11.5px; opacity: .9; margin-top: 4px; }
.banner .word { font-size: 34px; font-weight: 700; letter-spacing: 3px; }
.banner ul { margin: 0; padding-left: 18px; font-size: 13.5px; line-height: 1.45; }
.banner .none { font-size: 13.5px; }
table { border-collapse: collapse; width: 100%; margin: 4px 0 8px; font-variant-numeric: tabular-nums; }
th, td { padding: 4px 8px; border-bottom: 1px solid var(--rule); text-align: left; vertical-align: top; }
th { background: var(--band); font-weight: 600; font-size: 12px; color: #333c4a;
     -webkit-print-color-adjust: exact; print-color-adjust: exact; }
td.num, th.num { text-align: right; white-space: nowrap; }
tr { break-inside: avoid; page-break-inside: avoid; }
table.kv td:first-child { color: var(--muted); width: 42%; }
.grid2 { display: grid; grid-template-columns: minmax(0, 1fr) minmax(0, 1fr); gap: 18px; align-items: start; }
.status { font-weight: 700; font-size: 11.5px; letter-spacing: .5px; }
.status.ok { color: var(--pass); } .status.ng { color: var(--fail); } .status.nm { color: var(--nm); }
.status.ud { color: var(--ud); }
tr.ng td { background: #fdf0f0; -webkit-print-color-adjust: exact; print-color-adjust: exact; }
tr.ud td { background: #f4eefb; -webkit-print-color-adjust: exact; print-color-adjust: exact; }
.views { display: grid; grid-template-columns: minmax(0, 1fr) minmax(0, 1fr); gap: 10px 14px; }
figure { margin: 0; break-inside: avoid; page-break-inside: avoid; }
figure svg.view { width: 100%; height: auto; border: 1px solid var(--rule); background: #fff; }
figcaption { color: var(--muted); font-size: 11.5px; margin-top: 3px; }
svg { font-family: inherit; }
svg text { font-size: 11px; fill: var(--ink); }
svg .ttl { font-weight: 600; font-size: 12px; }
svg .grid { stroke: #e3e7ed; stroke-width: 1; }
svg .frame { fill: none; stroke: #7d8796; stroke-width: 1; }
svg rect.frame[fill] { stroke: #7d8796; }
svg .tick { stroke: #555; }
svg .tol { stroke: #111; stroke-width: 2; }
svg .tollabel { font-weight: 600; }
svg .ref { stroke: #888; stroke-dasharray: 4 3; }
svg .reflabel { fill: #666; font-size: 10px; }
svg polyline.s1 { fill: none; stroke: #2c5fb8; stroke-width: 1.8; } svg circle.s1 { fill: #2c5fb8; }
svg polyline.s2 { fill: none; stroke: #c0392b; stroke-width: 1.8; } svg circle.s2 { fill: #c0392b; }
svg .triad { font-size: 10px; font-weight: 700; }
svg line.axis { stroke-width: 3; stroke-linecap: round; }
svg polyline.cadedge { fill: none; stroke: #222; stroke-width: 2; stroke-dasharray: 6 4; }
svg polyline.scanedge { fill: none; stroke: #8e24aa; stroke-width: 2.5; }
svg line.axis.ok { stroke: var(--pass); } svg line.axis.ng { stroke: var(--fail); }
svg line.axis.nm { stroke: var(--nm); stroke-dasharray: 5 4; }
svg .blabel circle { stroke: #fff; stroke-width: 1.5; }
svg .blabel.ok circle { fill: var(--pass); } svg .blabel.ng circle { fill: var(--fail); }
svg .blabel.nm circle { fill: var(--nm); }
svg .blabel text { fill: #fff; font-weight: 700; font-size: 10.5px; }
svg line.arrow { stroke: #111; stroke-width: 1.6; }
svg line.halo { stroke: #fff; stroke-width: 4; stroke-linecap: round; }
svg circle.anchor { fill: #111; stroke: #fff; stroke-width: 0.8; }
svg .key rect { fill: #fff; fill-opacity: 0.85; stroke: #999; }
svg .key text { font-size: 12px; fill: #111; }
svg.chart { max-width: 100%; height: auto; }
svg.colorbar { width: 100%; height: auto; }
svg.colorbar text { font-size: 13px; }
table.bends { break-inside: avoid; page-break-inside: avoid; }
svg.spark { vertical-align: middle; color: var(--muted); }
.colorbar-wrap { margin: 2px 0 8px; }
.bar { display: inline-block; height: 9px; background: #6d88b5; vertical-align: middle;
       -webkit-print-color-adjust: exact; print-color-adjust: exact; }
.missing { border: 1px dashed var(--fail); color: var(--fail); padding: 14px; text-align: center; }
.note { color: var(--muted); }
ul.warnings { margin: 4px 0; padding-left: 18px; color: #8a5a00; }
footer { margin-top: 26px; border-top: 1px solid var(--rule); padding-top: 6px; color: var(--muted);
         font-size: 11px; }
section { break-inside: auto; }
.keep { break-inside: avoid; page-break-inside: avoid; }
.pagebreak { break-before: page; page-break-before: always; }
@media print {
  body { max-width: none; padding: 0; font-size: 11px; }
  .views { gap: 6px 10px; }
  h2 { margin-top: 14px; }
  .printbreak { break-before: page; page-break-before: always; }
}
)css";
}

}  // namespace springscan::report
