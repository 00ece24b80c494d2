#include "report/report_sections.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <numbers>
#include <utility>
#include <vector>

#include "report/html_text.hpp"

namespace springscan::report {
namespace {

// A two-column table of labels and values; both are plain text and get escaped here.
std::string kv_table(const std::vector<std::pair<std::string, std::string>>& rows) {
  std::string html = "<table class='kv'>";
  for (const auto& [label, value] : rows)
    html += "<tr><td>" + escape_html(label) + "</td><td class='num'>" + escape_html(value) +
            "</td></tr>";
  return html + "</table>";
}

std::string mm(double value, int decimals = 3) { return fixed(value, decimals) + " mm"; }
std::string count(std::int64_t n) { return std::to_string(n); }
std::string yes_no(bool value) { return value ? "yes" : "no"; }

std::string status_cell(const char* css, const char* word) {
  return std::string("<td><span class='status ") + css + "'>" + word + "</span></td>";
}

// A value and its expanded uncertainty U (k = 2): "0.98 &plusmn; 0.05"; the value alone where
// the report has no U (before the uncertainty stage, or 0).
std::string with_u(const std::string& value, double u, int decimals) {
  return u > 0.0 ? value + " &plusmn; " + fixed(u, decimals) : value;
}

// A characteristic's decision as a result cell; reports from before decisions: pass/fail.
std::string decision_cell(v1::Conformity decision, bool pass) {
  switch (decision) {
    case v1::CONFORMING:
      return status_cell("ok", "PASS");
    case v1::NONCONFORMING:
      return status_cell("ng", "FAIL");
    case v1::UNDECIDED:
      return status_cell("ud", "UNDECIDED");
    default:
      return pass ? status_cell("ok", "PASS") : status_cell("ng", "FAIL");
  }
}

// The part's word and banner class: the decision, or pass/fail for a report without one.
std::pair<const char*, const char*> verdict_word(const v1::Verdict& verdict) {
  if (verdict.decision() == v1::Verdict::UNDECIDED) return {"undecided", "UNDECIDED"};
  return verdict.pass() ? std::make_pair("pass", "PASS") : std::make_pair("fail", "FAIL");
}

// A small line of the angle along the bend: stations left to right, min to max bottom to top
// (a flat line when the spread is below 0.01 degrees).
std::string angle_sparkline(const v1::Bend& bend) {
  constexpr double kW = 72.0, kH = 18.0, kPad = 2.0;
  const auto& st = bend.angle_along_bend();
  if (st.size() < 2) return "";
  const double x0 = st.begin()->position_mm(), x1 = st.rbegin()->position_mm();
  const double lo = bend.angle_min_deg(), span = bend.angle_max_deg() - bend.angle_min_deg();
  std::string points;
  for (const auto& s : st) {
    const double x = kPad + (kW - 2 * kPad) * (s.position_mm() - x0) / std::max(x1 - x0, 1e-9);
    const double y =
        span < 0.01 ? 0.5 * kH : kH - kPad - (kH - 2 * kPad) * (s.angle_deg() - lo) / span;
    // Appended piece by piece (g++ 12 -Wrestrict false positive on "literal" + std::string).
    if (!points.empty()) points += ' ';
    points += fixed(x, 1);
    points += ',';
    points += fixed(y, 1);
  }
  return "<svg class='spark' width='72' height='18' viewBox='0 0 72 18' role='img' "
         "aria-label='angle along the bend'><polyline fill='none' stroke='currentColor' "
         "stroke-width='1.2' points='" +
         points + "'/></svg>";
}

// The angle along the bend: min to max, the spread and its little plot.
std::string along_cell(const v1::Bend& bend) {
  if (!bend.measured() || bend.angle_along_bend_size() == 0) return "<td class='num'>&mdash;</td>";
  return "<td class='num'>" + fixed(bend.angle_min_deg(), 2) + " &ndash; " +
         fixed(bend.angle_max_deg(), 2) + "<br>spread " + fixed(bend.angle_spread_deg(), 2) + " " +
         angle_sparkline(bend) + "</td>";
}

// Flatness (max, rms), curl radius ("flat" within noise) and twist of a flange.
std::string shape_cells(const v1::Segment& segment) {
  if (!segment.shape_measured())
    return "<td class='num'>&mdash;</td><td class='num'>&mdash;</td><td class='num'>&mdash;</td>";
  return "<td class='num'>" +
         with_u(fixed(segment.flatness_mm(), 3), segment.flatness_uncertainty_mm(), 3) + " (rms " +
         fixed(segment.flatness_rms_mm(), 3) + ")</td><td class='num'>" +
         (segment.has_curl_radius_mm() ? with_u(signed_fixed(segment.curl_radius_mm(), 0),
                                                segment.curl_radius_uncertainty_mm(), 0)
                                       : "flat") +
         "</td><td class='num'>" +
         (segment.has_twist_deg_per_100mm() ? signed_fixed(segment.twist_deg_per_100mm(), 3)
                                            : "&mdash;") +
         "</td>";
}

// An edge's U: in plane and across each its own (a report written before they were split: the
// one U of both).
std::string edge_uncertainty(const v1::EdgeDeviation& e) {
  if (e.in_plane_uncertainty_mm() > 0.0 || e.across_uncertainty_mm() > 0.0)
    return ", U " + fixed(e.in_plane_uncertainty_mm(), 2) + " in-plane, " +
           fixed(e.across_uncertainty_mm(), 2) + " across";
  return e.uncertainty_mm() > 0.0 ? ", U " + fixed(e.uncertainty_mm(), 2) : "";
}

// One trim edge against the CAD edge: mean along the sheet and across it, with their ranges.
std::string edge_line(const v1::EdgeDeviation& e) {
  return escape_html(e.kind().empty() ? "free" : e.kind()) + " edge: in-plane " +
         signed_fixed(e.in_plane_mean(), 2) + " (" + signed_fixed(e.in_plane_min(), 2) + " to " +
         signed_fixed(e.in_plane_max(), 2) + "), across " + signed_fixed(e.across_mean(), 2) +
         " (" + signed_fixed(e.across_min(), 2) + " to " + signed_fixed(e.across_max(), 2) + ")" +
         edge_uncertainty(e);
}

// The flange's measured trim edges, one line each (a report written before trim_edges: its
// free edge).
std::string edge_cell(const v1::Segment& segment) {
  std::string lines;
  for (const v1::EdgeDeviation& e : segment.trim_edges())
    lines += (lines.empty() ? "" : "<br>") + edge_line(e);
  if (lines.empty() && segment.has_edge_deviation_mm())
    lines = edge_line(segment.edge_deviation_mm());
  return "<td class='num'>" + (lines.empty() ? std::string("&mdash;") : lines) + "</td>";
}

}  // namespace

std::string header_html(const v1::InspectionReport& report) {
  const auto& input = report.input();
  const auto [css, word] = verdict_word(report.verdict());
  const bool pass = report.verdict().pass();
  std::string html =
      "<header class='top'><div><h1>Springback inspection report</h1><div "
      "class='sub'>Part <b>" +
      escape_html(input.part_id().empty() ? "(unnamed)" : input.part_id()) + "</b> &middot; CAD " +
      escape_html(input.cad_file()) + "</div></div>";
  html += "<div class='meta'>" + escape_html(report.created_utc()) + "<br>Station " +
          escape_html(report.station().empty() ? "(offline)" : report.station()) + "<br>Job " +
          std::to_string(report.job_id()) + " &middot; result " +
          std::to_string(report.result_seq()) + "</div></header>";
  html += std::string("<div class='banner ") + css + "' id='verdict'><div class='word'>" + word +
          "</div><div>";
  if (report.verdict().reasons_size() == 0) {
    html += std::string("<div class='none'>") +
            (pass ? "All checks within tolerance." : "No reason recorded.") + "</div>";
  } else {
    html += "<ul class='reasons'>";
    for (const auto& reason : report.verdict().reasons())
      html += "<li>" + escape_html(reason) + "</li>";
    html += "</ul>";
  }
  // Which rule decided (docs/report-format.md): a reader must know whether U was applied.
  if (report.verdict().decision() != v1::Verdict::DECISION_UNSPECIFIED) {
    html += report.verdict().decision_rule() == v1::VerdictSettings::SIMPLE
                ? "<div class='rule'>Decided by the simple rule: each value alone against its "
                  "limit, its uncertainty U not applied.</div>"
                : "<div class='rule'>Decided by the guard band (ISO 14253-1): a value conforms "
                  "when inside its limit by more than its expanded uncertainty U (k = 2), does "
                  "not when outside by more than U; in between the station cannot tell "
                  "(UNDECIDED: re-measure, then check by hand).</div>";
  }
  return html + "</div></div>";
}

std::string deviation_table(const v1::Deviation& d) {
  return kv_table(
      {{"Minimum (signed)", mm(d.min())},
       {"Maximum (signed)", mm(d.max())},
       {"Mean (signed)", mm(d.mean())},
       {"RMS", mm(d.rms())},
       {"95th percentile of |deviation|", mm(d.p95())},
       {"Out of tolerance", fixed(100.0 * d.fraction_out_of_tolerance(), 2) + " %"},
       {"Tolerance", "\u00b1" + mm(d.tolerance_mm())},
       {"Points", count(d.points())},
       {"U of the statistic judged (k = 2)",
        d.uncertainty_mm() > 0.0 ? mm(d.uncertainty_mm()) : "n/a"},
       {"Surface criterion",
        d.decision() == v1::CONFORMITY_UNSPECIFIED ? "n/a" : v1::Conformity_Name(d.decision())},
       {"Reference", d.reference().empty() ? "n/a" : d.reference()}});
}

std::string bend_table(const v1::InspectionReport& report) {
  std::string html =
      "<table class='bends'><tr><th>Bend</th><th class='num'>Nominal [\u00b0]</th>"
      "<th class='num'>Measured [\u00b0]</th><th class='num'>Springback [\u00b0]</th>"
      "<th class='num'>Tolerance [\u00b1\u00b0]</th><th class='num'>Along the bend [\u00b0]</th>"
      "<th class='num'>Radius [mm]</th><th class='num'>Measured radius [mm]</th>"
      "<th class='num'>Flanges</th><th>Result</th></tr>";
  for (const auto& bend : report.bends()) {
    const bool measured = bend.measured();
    const bool undecided = bend.decision() == v1::UNDECIDED;
    const char* row = !measured     ? "bend nm"
                      : undecided   ? "bend ud"
                      : bend.pass() ? "bend ok"
                                    : "bend ng";
    html += std::string("<tr class='") + row + "' id='bend-" + std::to_string(bend.id()) +
            "'><td><b>B" + std::to_string(bend.id()) + "</b></td><td class='num'>" +
            fixed(bend.nominal_angle_deg(), 2) + "</td><td class='num'>" +
            (measured ? with_u(fixed(bend.measured_angle_deg(), 2), bend.angle_uncertainty_deg(), 3)
                      : "&mdash;") +
            (measured && bend.end_tangents() ? "&dagger;" : "") + "</td><td class='num'>" +
            (measured ? with_u(signed_fixed(bend.springback_deg(), 2),
                               bend.springback_uncertainty_deg(), 3)
                      : "&mdash;") +
            "</td><td class='num'>" + fixed(bend.angle_tolerance_deg(), 2) + "</td>" +
            along_cell(bend) + "<td class='num'>" + fixed(bend.radius_mm(), 1) +
            "</td><td class='num'>" +
            (bend.has_measured_radius_mm()
                 ? with_u(fixed(bend.measured_radius_mm(), 2), bend.radius_uncertainty_mm(), 2)
                 : "&mdash;") +
            "</td><td class='num'>" + std::to_string(bend.segment_a()) + " / " +
            std::to_string(bend.segment_b()) + "</td>" +
            (!measured ? status_cell(undecided ? "ud" : "nm",
                                     undecided ? "NOT MEASURED: UNDECIDED" : "NOT MEASURED")
                       : decision_cell(bend.decision(), bend.pass())) +
            "</tr>";
  }
  return html +
         "</table><p class='note'>Springback = nominal &minus; measured angle: positive "
         "when the bend opened up. &plusmn; the expanded uncertainty U (k = 2, about 95 %) of "
         "that very scan. UNDECIDED: within U of the tolerance, or not measured. Along the bend: "
         "the angle at stations along the bend line "
         "(least to greatest, their spread). &dagger; Next to a curled flange: the angle "
         "between the tangent planes at the flanges' ends next to the bend (NUMISHEET'93), not "
         "between planes through the whole flanges.</p>";
}

std::string segment_table(const v1::InspectionReport& report) {
  std::string html =
      "<table class='segments'><tr><th>Flange</th><th class='num'>CAD faces</th>"
      "<th class='num'>Points</th><th class='num'>Local fit RMS [mm]</th>"
      "<th class='num'>Iterations</th><th>Converged</th><th class='num'>Flatness [mm]</th>"
      "<th class='num'>Curl radius [mm]</th><th class='num'>Twist [\u00b0/100 mm]</th>"
      "<th class='num'>Trim edges [mm]</th><th>Shape</th></tr>";
  for (const auto& segment : report.segments()) {
    std::string faces;
    for (int f : segment.cad_faces()) faces += (faces.empty() ? "" : ", ") + std::to_string(f);
    html += "<tr><td>S" + std::to_string(segment.id()) + "</td><td class='num'>" +
            escape_html(faces) + "</td><td class='num'>" + count(segment.points()) +
            "</td><td class='num'>" + fixed(segment.local_fit().rms(), 3) +
            "</td><td class='num'>" + std::to_string(segment.local_fit().iterations()) +
            "</td><td>" + yes_no(segment.local_fit().converged()) + "</td>" + shape_cells(segment) +
            edge_cell(segment) +
            (segment.shape_decision() == v1::CONFORMITY_UNSPECIFIED
                 ? std::string("<td>&mdash;</td>")
                 : decision_cell(segment.shape_decision(), false)) +
            "</tr>";
  }
  return html + "</table>";
}

// "± 0.012°"; n/a where the report has no U (before the uncertainty stage).
std::string plus_minus(double u, const char* unit) {
  return u > 0.0 ? "\u00b1 " + fixed(u, 3) + unit : "n/a";
}

// The frame the results are in: "datum", "best_fit", or the datum frame that was not made.
std::string result_frame(const v1::Alignment& a) {
  if (a.method().empty()) return "n/a";
  return a.achieved() || a.failure().empty() ? a.method()
                                             : a.method() + " (datum frame not achieved)";
}

std::string global_fit_table(const v1::InspectionReport& report) {
  const auto& fit = report.global_fit();
  std::string translation = "n/a", rotation = "n/a";
  if (fit.transform_size() == 16) {
    Eigen::Matrix4d T;
    for (int i = 0; i < 16; ++i) T(i / 4, i % 4) = fit.transform(i);  // row-major (DESIGN.md)
    const Eigen::AngleAxisd angle_axis(Eigen::Matrix3d(T.block<3, 3>(0, 0)));
    // Appended piece by piece: "(" + std::string triggers a g++ 12 -Wrestrict false positive.
    translation.assign(1, '(');
    translation += fixed(T(0, 3), 2) + ", " + fixed(T(1, 3), 2) + ", " + fixed(T(2, 3), 2);
    translation += ") mm";
    rotation = fixed(angle_axis.angle() * 180.0 / std::numbers::pi, 3) + "\u00b0";
  }
  return kv_table({{"Method", fit.method().empty() ? "n/a" : fit.method()},
                   {"Iterations", std::to_string(fit.iterations())},
                   {"Converged", yes_no(fit.converged())},
                   {"Stop reason", fit.stop_reason().empty() ? "n/a" : fit.stop_reason()},
                   {"RMS initial", mm(fit.rms_initial())},
                   {"RMS after PCA alignment", mm(fit.rms_after_pca())},
                   {"RMS final", mm(fit.rms_final())},
                   {"Inliers", count(fit.inliers())},
                   {"Translation scan \u2192 CAD", translation},
                   {"Rotation angle scan \u2192 CAD", rotation},
                   {"Result frame", result_frame(report.alignment())},
                   // The result frame's expanded uncertainty (k = 2): how far the frame every
                   // result is given in may be turned and moved (docs/uncertainty.md).
                   {"Result frame U rotation (k = 2)",
                    plus_minus(report.alignment().uncertainty_rotation_deg(), "\u00b0")},
                   {"Result frame U translation (k = 2)",
                    plus_minus(report.alignment().uncertainty_translation_mm(), " mm")}});
}

std::string reduction_table(const v1::ReductionReport& r) {
  return kv_table({{"Model points (in \u2192 reduced)",
                    count(r.model_points_in()) + " \u2192 " + count(r.model_points_out())},
                   {"Scan points (in \u2192 reduced)",
                    count(r.scan_points_in()) + " \u2192 " + count(r.scan_points_out())},
                   {"k-center radius w", mm(r.kcenter_radius_mm(), 2)},
                   {"Covering radius, model", mm(r.model_covering_radius_mm(), 2)},
                   {"Covering radius, scan", mm(r.scan_covering_radius_mm(), 2)}});
}

std::string deformation_table(const v1::InspectionReport& report) {
  const auto& field = report.deformation_field();
  double longest = 0.0, sum = 0.0;
  for (const auto& c : report.compensation()) {
    const double n = std::sqrt(c.vector().x() * c.vector().x() + c.vector().y() * c.vector().y() +
                               c.vector().z() * c.vector().z());
    longest = std::max(longest, n);
    sum += n;
  }
  const int n = report.compensation_size();
  return kv_table(
      {{"Correspondence method", field.method().empty() ? "n/a" : field.method()},
       {"Correspondences", std::to_string(field.vectors_size())},
       {"Model / scan points matched",
        std::to_string(field.model_points()) + " / " + std::to_string(field.scan_points())},
       {"Coverage", fixed(100.0 * field.coverage(), 1) + " %"},
       {"Total cost (sum of squared distances)", fixed(field.total_cost(), 3) + " mm\u00b2"},
       {"Optimality certified", yes_no(field.optimality_certified())},
       {"Compensation vectors", std::to_string(n)},
       {"Largest |c|", mm(longest)},
       {"Mean |c|", n > 0 ? mm(sum / n) : "n/a"}});
}

std::string timings_table(const v1::Timings& t) {
  const std::vector<std::pair<const char*, double>> stages = {{"Load", t.load()},
                                                              {"Model sampling", t.model()},
                                                              {"Reduction", t.reduce()},
                                                              {"Global fit", t.global_fit()},
                                                              {"Deviation", t.deviation()},
                                                              {"Local fits", t.local_fits()},
                                                              {"Deformation", t.deformation()},
                                                              {"Report", t.report()}};
  double longest = 1e-9;
  for (const auto& s : stages) longest = std::max(longest, s.second);
  std::string html =
      "<table class='timings'><tr><th>Stage</th><th class='num'>Time [ms]</th>"
      "<th></th></tr>";
  for (const auto& [name, ms] : stages) {
    const double width = std::clamp(ms / longest, 0.0, 1.0) * 160.0;
    html += std::string("<tr><td>") + name + "</td><td class='num'>" + fixed(ms, 1) +
            "</td><td><span class='bar' style='width:" + svg_number(width) +
            "px'></span></td></tr>";
  }
  return html + "<tr><th>Total</th><th class='num'>" + fixed(t.total(), 1) +
         "</th><th></th></tr></table>";
}

std::string input_table(const v1::InspectionReport& report) {
  const auto& in = report.input();
  return kv_table({{"CAD file", in.cad_file()},
                   {"CAD SHA-256", in.cad_sha256().substr(0, 16)},
                   {"CAD faces", std::to_string(in.cad_faces())},
                   {"Model sample points", count(in.model_points())},
                   {"Scan file", in.scan_file()},
                   {"Scan points", count(in.scan_points())}});
}

std::string warnings_html(const v1::InspectionReport& report) {
  if (report.warnings_size() == 0) return "";
  std::string html = "<section id='warnings' class='keep'><h2>Warnings</h2><ul class='warnings'>";
  for (const auto& w : report.warnings()) html += "<li>" + escape_html(w) + "</li>";
  return html + "</ul></section>";
}

std::string footer_html(const v1::InspectionReport& report) {
  return "<footer>springscan " + escape_html(report.software_version()) + " &middot; " +
         escape_html(report.schema()) +
         " &middot; distances in mm, angles in degrees, CAD coordinate frame</footer>";
}

}  // namespace springscan::report
