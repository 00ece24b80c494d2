#include "report/msa_html.hpp"

#include <cmath>
#include <optional>

#include "report/html_text.hpp"
#include "report/msa_charts.hpp"
#include "report/msa_stats.hpp"

namespace springscan::report {

namespace {

const char* kStyle = R"(
body{font-family:system-ui,-apple-system,"Segoe UI",sans-serif;margin:24px;color:#1d232b;
  background:#fff;max-width:1000px}
h1{font-size:22px;margin:0 0 4px}h2{font-size:17px;margin:28px 0 6px}
.meta{color:#5a6470;font-size:13px;margin-bottom:14px}
table{border-collapse:collapse;font-size:13px;width:100%}
th,td{border-bottom:1px solid #dde2e8;padding:4px 6px;text-align:right}
th:first-child,td:first-child{text-align:left}
th{background:#f1f4f7}
td.bad{background:#f8d7d4;color:#8a1c12;font-weight:600}
td.warn{background:#fdf0cc;color:#6b4d00}
td.good{background:#dff2e1;color:#1c5d27}
.charts{display:flex;flex-wrap:wrap;gap:8px}
svg{display:block;background:#fbfcfd;border:1px solid #e3e7ec}
)";

std::string cell(const std::string& text, const char* css = "") {
  return std::string("<td") + (css[0] ? std::string(" class=\"") + css + "\"" : "") + ">" + text +
         "</td>";
}

std::string optional_text(bool has, double v, int decimals) {
  return has ? fixed(v, decimals) : "&ndash;";
}

std::string value_text(double v) {
  const double a = std::abs(v);
  return fixed(v, a >= 100 ? 1 : a >= 1 ? 3 : 5);
}

std::string head(const std::string& title, const std::string& part_id, int reports,
                 const MsaPageInfo& info, const std::string& method) {
  std::string html = "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>" +
                     escape_html(title) + "</title><style>" + kStyle +
                     "</style></head><body>\n<h1>" + escape_html(title) +
                     "</h1>\n<div class=\"meta\">part " + escape_html(part_id) + ", " +
                     std::to_string(reports) + " reports";
  if (!info.first_utc.empty())
    html += " from " + escape_html(info.first_utc) + " to " + escape_html(info.last_utc);
  html += "<br>read from ";
  for (std::size_t i = 0; i < info.sources.size(); ++i)
    html += (i ? ", " : "") + escape_html(info.sources[i]);
  return html + "<br>" + method + "</div>\n";
}

std::string anchor(std::size_t i) { return std::string(1, 'c').append(std::to_string(i + 1)); }

}  // namespace

std::string render_type1_html(const v1::MsaType1Study& study, const MsaPageInfo& info) {
  std::string html = head(info.title.empty() ? "springscan msa type 1" : info.title,
                          study.part_id(), study.reports(), info,
                          "Type 1 study: s with n &minus; 1; Cg = 0.2&middot;T / (6 s), Cgk = "
                          "(0.1&middot;T &minus; |bias|) / (3 s), capable at 1.33 and above; "
                          "bias t-test two-sided at 5 %.");
  html += std::string("<p class=\"verdict\">") +
          (study.capable() ? "Capable: every characteristic has Cg and Cgk &ge; 1.33."
                           : "<b>Not capable</b>: see the characteristics marked.") +
          "</p>\n<table id=\"characteristics\"><thead><tr><th>characteristic</th><th>T</th>"
          "<th>n</th><th>reference</th><th>mean</th><th>s</th><th>bias</th><th>t</th><th>p</th>"
          "<th>Cg</th><th>Cgk</th><th>verdict</th></tr></thead><tbody>\n";
  for (int i = 0; i < study.characteristics_size(); ++i) {
    const v1::MsaType1Characteristic& c = study.characteristics(i);
    const char* cls = c.capable() ? "good" : "bad";
    html += "<tr class=\"characteristic\">" +
            cell("<a href=\"#" + anchor(static_cast<std::size_t>(i)) + "\">" +
                 escape_html(c.name()) + "</a> (" + escape_html(c.unit()) + ")") +
            cell(value_text(c.tolerance())) + cell(std::to_string(c.n())) +
            cell(value_text(c.reference())) + cell(value_text(c.mean())) +
            cell(value_text(c.stddev())) + cell(signed_fixed(c.bias(), 5)) +
            cell(fixed(c.bias_t(), 2)) +
            cell(fixed(c.bias_p(), 3), c.bias_significant() ? "warn" : "") +
            cell(optional_text(c.has_cg(), c.cg(), 2), cls) +
            cell(optional_text(c.has_cgk(), c.cgk(), 2), cls) +
            cell(c.capable() ? "capable" : "not capable", cls) + "</tr>\n";
  }
  html += "</tbody></table>\n";
  for (int i = 0; i < study.characteristics_size(); ++i) {
    const v1::MsaType1Characteristic& c = study.characteristics(i);
    const std::vector<double> values(c.values().begin(), c.values().end());
    const double band = 0.1 * c.tolerance();
    std::vector<ChartLine> lines{{c.reference(), "ref " + value_text(c.reference()), "#2f7d32"},
                                 {c.mean(), "mean " + value_text(c.mean()), "#44505c", true}};
    if (band > 0) {
      lines.push_back({c.reference() + band, "ref + 0.1 T", "#c0392b", true});
      lines.push_back({c.reference() - band, "ref &minus; 0.1 T", "#c0392b", true});
    }
    html += "<section id=\"" + anchor(static_cast<std::size_t>(i)) + "\"><h2>" +
            escape_html(c.name()) + "</h2>\n<div class=\"charts\">" +
            run_chart_svg(values, lines, c.unit()) + histogram_svg(values, lines, c.unit()) +
            "</div></section>\n";
  }
  return html + "</body></html>\n";
}

std::string render_type3_html(const v1::MsaType3Study& study, const MsaPageInfo& info) {
  std::string html = head(info.title.empty() ? "springscan msa type 3" : info.title,
                          study.part_id(), study.reports(), info,
                          "Type 3 study (automated gauge, no operator): one-way ANOVA of parts "
                          "with repeats; EV = &radic;MS<sub>within</sub>, GRR = EV, PV = "
                          "&radic;max(0, (MS<sub>parts</sub> &minus; MS<sub>within</sub>) / r); "
                          "%GRR of T = 600&middot;GRR / T; ndc = 1.41&middot;PV / GRR. "
                          "Acceptable: %GRR &le; 10 % and ndc &ge; 5; up to 30 %: conditionally.");
  html += std::string("<p class=\"verdict\">") +
          (study.acceptable() ? "Acceptable: every characteristic within %GRR 10 % and ndc 5."
                              : "<b>Not acceptable</b>: see the characteristics marked.") +
          "</p>\n<table id=\"characteristics\"><thead><tr><th>characteristic</th><th>T</th>"
          "<th>parts</th><th>trials</th><th>EV</th><th>PV</th><th>GRR</th><th>%GRR of T</th>"
          "<th>%GRR of TV</th><th>ndc</th><th>verdict</th></tr></thead><tbody>\n";
  for (int i = 0; i < study.characteristics_size(); ++i) {
    const v1::MsaType3Characteristic& c = study.characteristics(i);
    const char* cls = c.acceptable()                                                     ? "good"
                      : c.verdict() == to_string(GrrVerdict::kConditional) && c.ndc_ok() ? "warn"
                                                                                         : "bad";
    html += "<tr class=\"characteristic\">" +
            cell("<a href=\"#" + anchor(static_cast<std::size_t>(i)) + "\">" +
                 escape_html(c.name()) + "</a> (" + escape_html(c.unit()) + ")") +
            cell(value_text(c.tolerance())) + cell(std::to_string(c.parts())) +
            cell(std::to_string(c.trials())) + cell(value_text(c.ev())) + cell(value_text(c.pv())) +
            cell(value_text(c.grr())) +
            cell(optional_text(c.has_grr_pct_tolerance(), c.grr_pct_tolerance(), 1), cls) +
            cell(optional_text(c.has_grr_pct_total(), c.grr_pct_total(), 1)) +
            cell(optional_text(c.has_ndc(), c.ndc(), 1), c.ndc_ok() ? "" : "bad") +
            cell(escape_html(c.verdict()) + (c.ndc_ok() ? "" : ", ndc &lt; 5"), cls) + "</tr>\n";
  }
  html += "</tbody></table>\n";
  for (int i = 0; i < study.characteristics_size(); ++i) {
    const v1::MsaType3Characteristic& c = study.characteristics(i);
    const std::vector<double> values(c.values().begin(), c.values().end());
    html += "<section id=\"" + anchor(static_cast<std::size_t>(i)) + "\"><h2>" +
            escape_html(c.name()) + "</h2>\n" +
            parts_chart_svg(values, static_cast<std::size_t>(c.parts()),
                            static_cast<std::size_t>(c.trials()), c.unit()) +
            "</section>\n";
  }
  return html + "</body></html>\n";
}

}  // namespace springscan::report
