#include "report/trend_html.hpp"

#include <algorithm>
#include <cmath>

#include "report/html_text.hpp"

namespace springscan::report {

namespace {

constexpr double kWidth = 960.0;
constexpr double kLeft = 70.0, kRight = 20.0, kTop = 14.0, kBottom = 26.0;

const char* kStyle = R"(
body{font-family:system-ui,-apple-system,"Segoe UI",sans-serif;margin:24px;color:#1d232b;
  background:#fff;max-width:1000px}
h1{font-size:22px;margin:0 0 4px}h2{font-size:17px;margin:28px 0 6px}
.meta{color:#5a6470;font-size:13px;margin-bottom:14px}
table{border-collapse:collapse;font-size:13px;width:100%}
th,td{border-bottom:1px solid #dde2e8;padding:4px 6px;text-align:right}
th:nth-child(-n+2),td:nth-child(-n+2){text-align:left}
th{background:#f1f4f7}
td.bad{background:#f8d7d4;color:#8a1c12;font-weight:600}
td.warn{background:#fdf0cc;color:#6b4d00}
td.good{background:#dff2e1;color:#1c5d27}
.stats{font-size:13px;color:#333;margin:2px 0 6px}
svg{display:block;background:#fbfcfd;border:1px solid #e3e7ec;margin-bottom:6px}
.legend{font-size:12px;color:#5a6470}
.legend span{margin-right:14px}
)";

std::string num(double v) { return svg_number(v); }

std::string value_text(double v) {
  const double a = std::abs(v);
  return fixed(v, a >= 100 ? 1 : a >= 1 ? 3 : 4);
}

std::string optional_text(const std::optional<double>& v, int decimals = 3) {
  return v ? fixed(*v, decimals) : "&ndash;";
}

std::string rules_text(std::uint8_t bits) {
  std::string text;
  const char* names[] = {"rule 1: beyond 3 sigma", "rule 2: 2 of 3 beyond 2 sigma",
                         "rule 3: 4 of 5 beyond 1 sigma", "rule 4: 8 on one side"};
  for (int r = 0; r < 4; ++r) {
    if ((bits & (1 << r)) == 0) continue;
    if (!text.empty()) text += "; ";
    text += names[r];
  }
  return text;
}

// The median U of a characteristic's values (those that have one); nothing when none has.
std::string median_u_text(const Characteristic& c) {
  std::vector<double> u;
  for (const double x : c.uncertainties)
    if (x > 0.0) u.push_back(x);
  if (u.empty()) return "&ndash;";
  std::nth_element(u.begin(), u.begin() + static_cast<std::ptrdiff_t>(u.size() / 2), u.end());
  return value_text(u[u.size() / 2]);
}

std::string anchor(std::size_t index) {
  // Built by append: `"c" + std::to_string(...)` trips a g++ 12 -Wrestrict false positive.
  std::string id(1, 'c');
  return id.append(std::to_string(index + 1));
}

/// Maps values to the chart's pixels.
struct Scale {
  double lo, hi, top, height, left, width;
  std::size_t n;
  double x(std::size_t i) const {
    return left +
           (n <= 1 ? 0.5 * width : width * static_cast<double>(i) / static_cast<double>(n - 1));
  }
  double y(double v) const { return top + height * (hi - v) / (hi - lo); }
};

Scale make_scale(const std::vector<double>& values, std::vector<double> also, double height) {
  also.insert(also.end(), values.begin(), values.end());
  double lo = *std::min_element(also.begin(), also.end());
  double hi = *std::max_element(also.begin(), also.end());
  if (!(hi > lo)) {
    lo -= 1e-3 + std::abs(lo) * 0.05;
    hi += 1e-3 + std::abs(hi) * 0.05;
  }
  const double pad = 0.06 * (hi - lo);
  return Scale{
      lo - pad,     hi + pad, kTop, height - kTop - kBottom, kLeft, kWidth - kLeft - kRight,
      values.size()};
}

void horizontal(std::string& svg, const Scale& s, double v, const char* colour, const char* dash,
                const std::string& text) {
  const std::string y = num(s.y(v));
  svg += "<line x1=\"" + num(s.left) + "\" x2=\"" + num(s.left + s.width) + "\" y1=\"" + y +
         "\" y2=\"" + y + "\" stroke=\"" + colour + "\" stroke-width=\"1.2\"";
  if (dash[0] != '\0') svg += std::string(" stroke-dasharray=\"") + dash + "\"";
  svg += "/><text x=\"" + num(s.left + s.width - 4) + "\" y=\"" + num(s.y(v) - 3) +
         "\" font-size=\"11\" text-anchor=\"end\" fill=\"" + colour + "\">" + text + "</text>";
}

void axes(std::string& svg, const Scale& s, const std::string& unit) {
  svg += "<rect x=\"" + num(s.left) + "\" y=\"" + num(s.top) + "\" width=\"" + num(s.width) +
         "\" height=\"" + num(s.height) + "\" fill=\"none\" stroke=\"#c5ccd4\"/>";
  for (int k = 0; k <= 4; ++k) {
    const double v = s.lo + (s.hi - s.lo) * k / 4.0;
    svg += "<text x=\"" + num(s.left - 6) + "\" y=\"" + num(s.y(v) + 4) +
           "\" font-size=\"11\" text-anchor=\"end\" fill=\"#5a6470\">" + value_text(v) + "</text>";
  }
  svg += "<text x=\"12\" y=\"" + num(s.top + s.height / 2) +
         "\" font-size=\"11\" fill=\"#5a6470\" transform=\"rotate(-90 12 " +
         num(s.top + s.height / 2) + ")\" text-anchor=\"middle\">" + escape_html(unit) + "</text>";
  svg += "<text x=\"" + num(s.left) + "\" y=\"" + num(s.top + s.height + 16) +
         "\" font-size=\"11\" fill=\"#5a6470\">1</text><text x=\"" + num(s.left + s.width) +
         "\" y=\"" + num(s.top + s.height + 16) +
         "\" font-size=\"11\" text-anchor=\"end\" fill=\"#5a6470\">" + std::to_string(s.n) +
         " (reports in time order)</text>";
}

void polyline(std::string& svg, const Scale& s, const std::vector<double>& values,
              std::size_t offset, const char* colour) {
  svg += "<polyline fill=\"none\" stroke=\"";
  svg += colour;
  svg += "\" stroke-width=\"1\" points=\"";
  for (std::size_t i = 0; i < values.size(); ++i) {
    if (i != 0) svg.push_back(' ');
    svg += num(s.x(i + offset));
    svg.push_back(',');
    svg += num(s.y(values[i]));
  }
  svg += "\"/>";
}

std::string individuals_svg(const Characteristic& c, std::size_t max_markers) {
  const ControlChart& ch = c.chart;
  std::vector<double> lines{ch.mean, ch.ucl, ch.lcl};
  if (c.lsl) lines.push_back(*c.lsl);
  if (c.usl) lines.push_back(*c.usl);
  const double height = 280.0;
  const Scale s = make_scale(c.values, lines, height);
  std::string svg = "<svg class=\"individuals\" xmlns=\"http://www.w3.org/2000/svg\" width=\"" +
                    num(kWidth) + "\" height=\"" + num(height) + "\" viewBox=\"0 0 " + num(kWidth) +
                    " " + num(height) + "\" role=\"img\" aria-label=\"" + escape_html(c.name) +
                    " individuals chart\">";
  axes(svg, s, c.unit);
  if (c.usl) horizontal(svg, s, *c.usl, "#c0392b", "", "USL " + value_text(*c.usl));
  if (c.lsl) horizontal(svg, s, *c.lsl, "#c0392b", "", "LSL " + value_text(*c.lsl));
  horizontal(svg, s, ch.ucl, "#2f6fb5", "6 4", "UCL " + value_text(ch.ucl));
  horizontal(svg, s, ch.lcl, "#2f6fb5", "6 4", "LCL " + value_text(ch.lcl));
  horizontal(svg, s, ch.mean, "#44505c", "", "X&#772; " + value_text(ch.mean));
  polyline(svg, s, c.values, 0, "#7d8a97");
  const bool all_markers = c.values.size() <= max_markers;
  for (std::size_t i = 0; i < c.values.size(); ++i) {
    const bool flagged = ch.rules[i] != 0;
    if (!flagged && !all_markers) continue;
    svg += "<circle cx=\"" + num(s.x(i)) + "\" cy=\"" + num(s.y(c.values[i])) + "\" r=\"" +
           (flagged ? "3.6" : "2.4") + "\" fill=\"" + (flagged ? "#d62d20" : "#2b3a4a") + "\"" +
           (flagged ? " class=\"flagged\"" : "") + "><title>" + escape_html(c.labels[i]) + ": " +
           value_text(c.values[i]) +
           (i < c.uncertainties.size() && c.uncertainties[i] > 0.0
                ? " &plusmn; " + value_text(c.uncertainties[i])
                : "") +
           " " + escape_html(c.unit) + (flagged ? " (" + rules_text(ch.rules[i]) + ")" : "") +
           "</title></circle>";
  }
  return svg + "</svg>";
}

std::string moving_range_svg(const Characteristic& c) {
  const ControlChart& ch = c.chart;
  const double height = 150.0;
  std::vector<double> mr = ch.moving_range;
  Scale s = make_scale(mr.empty() ? std::vector<double>{0.0} : mr, {0.0, ch.mr_ucl}, height);
  s.n = c.values.size();
  std::string svg = "<svg class=\"moving-range\" xmlns=\"http://www.w3.org/2000/svg\" width=\"" +
                    num(kWidth) + "\" height=\"" + num(height) + "\" viewBox=\"0 0 " + num(kWidth) +
                    " " + num(height) + "\" role=\"img\" aria-label=\"" + escape_html(c.name) +
                    " moving range chart\">";
  axes(svg, s, "MR " + c.unit);
  horizontal(svg, s, ch.mr_ucl, "#2f6fb5", "6 4", "UCL " + value_text(ch.mr_ucl));
  horizontal(svg, s, ch.mr_bar, "#44505c", "", "MR&#772; " + value_text(ch.mr_bar));
  if (!mr.empty()) polyline(svg, s, mr, 1, "#2b3a4a");
  return svg + "</svg>";
}

std::string cpk_class(const std::optional<double>& cpk) {
  if (!cpk) return "";
  if (*cpk < 1.0) return " class=\"bad\"";
  if (*cpk < 1.33) return " class=\"warn\"";
  return " class=\"good\"";
}

}  // namespace

std::string render_trend_html(const std::vector<Characteristic>& characteristics,
                              const TrendPageInfo& info, std::size_t max_markers) {
  std::string html;
  html.reserve(4096 + characteristics.size() * 64 * 1024);
  html += "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>" +
          escape_html(info.title) + "</title><style>" + kStyle + "</style></head><body>\n";
  html += "<h1>" + escape_html(info.title) + "</h1>\n<div class=\"meta\">" +
          std::to_string(info.reports) + " reports";
  if (!info.first_utc.empty())
    html += " from " + escape_html(info.first_utc) + " to " + escape_html(info.last_utc);
  if (info.skipped != 0) html += "; " + std::to_string(info.skipped) + " files skipped";
  html += "<br>read from ";
  for (std::size_t i = 0; i < info.sources.size(); ++i)
    html += (i ? ", " : "") + escape_html(info.sources[i]);
  html +=
      "<br>Individuals charts: control limits X&#772; &plusmn; 2.66 MR&#772; (3&sigma;, "
      "&sigma; = MR&#772;/1.128); Cp and Cpk from that short-term &sigma;; points breaking a "
      "Western Electric rule in red.<br>Part decisions (ISO 14253-1 guard band unless the "
      "reports say SIMPLE): " +
      std::to_string(info.decisions.pass) + " PASS, " + std::to_string(info.decisions.fail) +
      " FAIL, " + std::to_string(info.decisions.undecided) + " UNDECIDED, " +
      std::to_string(info.decisions.none) + " without a decision.</div>\n";

  html +=
      "<h2>Characteristics by Cpk</h2>\n<table id=\"characteristics\"><thead><tr><th>part</th>"
      "<th>characteristic</th><th>n</th><th>X&#772;</th><th>&sigma;</th><th>LCL</th><th>UCL</th>"
      "<th>LSL</th><th>USL</th><th>Cp</th><th>Cpk</th><th>flagged</th><th>median U</th>"
      "<th>undecided</th><th>nonconforming</th></tr></thead><tbody>\n";
  for (std::size_t i = 0; i < characteristics.size(); ++i) {
    const Characteristic& c = characteristics[i];
    const ControlChart& ch = c.chart;
    html += "<tr class=\"characteristic\"><td>" + escape_html(c.part_id) + "</td><td><a href=\"#" +
            anchor(i) + "\">" + escape_html(c.name) + "</a> (" + escape_html(c.unit) +
            ")</td><td>" + std::to_string(ch.n) + "</td><td>" + value_text(ch.mean) + "</td><td>" +
            value_text(ch.sigma) + "</td><td>" + value_text(ch.lcl) + "</td><td>" +
            value_text(ch.ucl) + "</td><td>" + optional_text(c.lsl) + "</td><td>" +
            optional_text(c.usl) + "</td><td>" + optional_text(ch.cp, 2) + "</td><td" +
            cpk_class(ch.cpk) + ">" + optional_text(ch.cpk, 2) + "</td><td>" +
            std::to_string(ch.points_flagged) + "</td><td>" + median_u_text(c) + "</td><td>" +
            std::to_string(c.undecided) + "</td><td>" + std::to_string(c.nonconforming) +
            "</td></tr>\n";
  }
  html += "</tbody></table>\n";

  for (std::size_t i = 0; i < characteristics.size(); ++i) {
    const Characteristic& c = characteristics[i];
    const ControlChart& ch = c.chart;
    std::size_t per_rule[4] = {0, 0, 0, 0};
    for (const std::uint8_t bits : ch.rules)
      for (int r = 0; r < 4; ++r) per_rule[r] += (bits >> r) & 1u;
    html += "<section id=\"" + anchor(i) + "\"><h2>part " + escape_html(c.part_id) + " &middot; " +
            escape_html(c.name) + "</h2>\n<div class=\"stats\">n " + std::to_string(ch.n) +
            " &middot; X&#772; " + value_text(ch.mean) + " " + escape_html(c.unit) +
            " &middot; MR&#772; " + value_text(ch.mr_bar) + " &middot; &sigma; " +
            value_text(ch.sigma) + " &middot; Cp " + optional_text(ch.cp, 2) + " &middot; Cpk " +
            optional_text(ch.cpk, 2) + " &middot; rule 1: " + std::to_string(per_rule[0]) +
            ", rule 2: " + std::to_string(per_rule[1]) +
            ", rule 3: " + std::to_string(per_rule[2]) +
            ", rule 4: " + std::to_string(per_rule[3]) + " points</div>\n";
    html += individuals_svg(c, max_markers) + "\n" + moving_range_svg(c) + "\n";
    html +=
        "<div class=\"legend\"><span style=\"color:#c0392b\">&#9473; tolerance</span>"
        "<span style=\"color:#2f6fb5\">&#9476; control limit</span><span "
        "style=\"color:#d62d20\">&#9679; Western Electric rule broken</span></div></section>\n";
  }
  html += "</body></html>\n";
  return html;
}

}  // namespace springscan::report
