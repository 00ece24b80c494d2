#include "report/trend.hpp"

#include <google/protobuf/arena.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <map>
#include <thread>
#include <tuple>

#include "analysis/io/file_io.hpp"

namespace springscan::report {

namespace fs = std::filesystem;

namespace {

constexpr double kD2 = 1.128;  // d2 for moving ranges of 2 (Montgomery, Appendix VI)
constexpr double kE2 = 2.66;   // 3 / d2: X-bar +- E2 MR-bar
constexpr double kD4 = 3.267;  // MR chart upper limit factor

/// Flags the points of every window of `length` consecutive points in which at least `needed`
/// lie beyond `limit` sigma on one side (only those points are flagged).
void flag_windows(const std::vector<double>& z, std::size_t length, std::size_t needed,
                  double limit, std::uint8_t bit, std::vector<std::uint8_t>& rules) {
  if (z.size() < length) return;
  for (std::size_t end = length - 1; end < z.size(); ++end) {
    const std::size_t begin = end + 1 - length;
    for (const double side : {1.0, -1.0}) {
      std::size_t count = 0;
      for (std::size_t i = begin; i <= end; ++i) count += side * z[i] > limit ? 1 : 0;
      if (count < needed) continue;
      for (std::size_t i = begin; i <= end; ++i)
        if (side * z[i] > limit) rules[i] |= bit;
    }
  }
}

std::string label(const v1::InspectionReport& r) {
  std::string text = "seq " + std::to_string(r.result_seq());
  if (r.job_id() != 0) text += ", job " + std::to_string(r.job_id());
  if (!r.created_utc().empty()) text += ", " + r.created_utc();
  return text;
}

}  // namespace

ControlChart control_chart(const std::vector<double>& values, std::optional<double> lsl,
                           std::optional<double> usl) {
  ControlChart c;
  c.n = values.size();
  c.rules.assign(values.size(), 0);
  if (values.empty()) return c;
  double sum = 0.0;
  for (const double v : values) sum += v;
  c.mean = sum / static_cast<double>(values.size());
  if (values.size() >= 2) {
    c.moving_range.reserve(values.size() - 1);
    double mr_sum = 0.0;
    for (std::size_t i = 1; i < values.size(); ++i) {
      c.moving_range.push_back(std::abs(values[i] - values[i - 1]));
      mr_sum += c.moving_range.back();
    }
    c.mr_bar = mr_sum / static_cast<double>(c.moving_range.size());
  }
  c.sigma = c.mr_bar / kD2;
  c.ucl = c.mean + kE2 * c.mr_bar;
  c.lcl = c.mean - kE2 * c.mr_bar;
  c.mr_ucl = kD4 * c.mr_bar;
  if (c.sigma > 0.0) {
    if (lsl && usl) c.cp = (*usl - *lsl) / (6.0 * c.sigma);
    if (lsl || usl) {
      double cpk = std::numeric_limits<double>::infinity();
      if (usl) cpk = std::min(cpk, (*usl - c.mean) / (3.0 * c.sigma));
      if (lsl) cpk = std::min(cpk, (c.mean - *lsl) / (3.0 * c.sigma));
      c.cpk = cpk;
    }
    std::vector<double> z(values.size());
    for (std::size_t i = 0; i < values.size(); ++i) z[i] = (values[i] - c.mean) / c.sigma;
    flag_windows(z, 1, 1, 3.0, kRuleBeyond3Sigma, c.rules);
    flag_windows(z, 3, 2, 2.0, kRule2Of3Beyond2Sigma, c.rules);
    flag_windows(z, 5, 4, 1.0, kRule4Of5Beyond1Sigma, c.rules);
    flag_windows(z, 8, 8, 0.0, kRule8OnOneSide, c.rules);
  }
  for (const std::uint8_t r : c.rules) c.points_flagged += r != 0 ? 1 : 0;
  return c;
}

namespace {

// Beyond rigid flanges: each bend's angle spread along the bend, each flange's flatness, curl
// radius and twist where the report measured them, with the verdict's limits in force, and the
// U of flatness and curl radius and the flange's shape decision.
template <typename Add>
void add_shape_characteristics(const v1::InspectionReport& r, const Add& add) {
  const v1::VerdictSettings& limits = r.settings().verdict();
  const auto upper = [](bool has, double v) {
    return has && v > 0 ? std::optional<double>(v) : std::nullopt;
  };
  for (const v1::Bend& b : r.bends())
    if (b.measured() && b.angle_along_bend_size() > 0)
      add(r, "bend " + std::to_string(b.id()) + " angle spread", "deg", b.angle_spread_deg(),
          std::nullopt, upper(limits.has_max_angle_spread_deg(), limits.max_angle_spread_deg()));
  for (const v1::Segment& seg : r.segments()) {
    const std::string name = "flange " + std::to_string(seg.id());
    if (seg.points() > 0)
      add(r, name + " flatness", "mm", seg.flatness_mm(), std::nullopt,
          upper(limits.has_max_flatness_mm(), limits.max_flatness_mm()),
          seg.flatness_uncertainty_mm(), seg.shape_decision());
    if (seg.has_curl_radius_mm())
      add(r, name + " curl radius", "mm", seg.curl_radius_mm(), std::nullopt, std::nullopt,
          seg.curl_radius_uncertainty_mm(), v1::CONFORMITY_UNSPECIFIED);
    if (seg.has_twist_deg_per_100mm())
      add(r, name + " twist", "deg/100 mm", seg.twist_deg_per_100mm(), std::nullopt, std::nullopt);
  }
}

}  // namespace

std::vector<Characteristic> collect_characteristics(
    const std::vector<v1::InspectionReport>& reports) {
  std::vector<Characteristic> out;
  std::map<std::pair<std::string, std::string>, std::size_t> index;
  const auto add = [&](const v1::InspectionReport& r, const std::string& name, const char* unit,
                       double value, std::optional<double> lsl, std::optional<double> usl,
                       double u = 0.0, v1::Conformity decision = v1::CONFORMITY_UNSPECIFIED) {
    if (!std::isfinite(value)) return;
    const auto key = std::make_pair(r.input().part_id(), name);
    auto found = index.find(key);
    if (found == index.end()) {
      found = index.emplace(key, out.size()).first;
      out.push_back(Characteristic{r.input().part_id(), name, unit, {}, {}, {}, {}, {}});
    }
    Characteristic& c = out[found->second];
    c.values.push_back(value);
    c.labels.push_back(label(r));
    c.uncertainties.push_back(std::isfinite(u) ? u : 0.0);
    c.undecided += decision == v1::UNDECIDED ? 1 : 0;
    c.nonconforming += decision == v1::NONCONFORMING ? 1 : 0;
    // The limits in force in the newest report.
    c.lsl = lsl;
    c.usl = usl;
  };
  for (const v1::InspectionReport& r : reports) {
    for (const v1::Bend& b : r.bends()) {
      if (!b.measured()) continue;
      const double tol = b.angle_tolerance_deg();
      add(r, "bend " + std::to_string(b.id()) + " springback", "deg", b.springback_deg(),
          tol > 0 ? std::optional<double>(-tol) : std::nullopt,
          tol > 0 ? std::optional<double>(tol) : std::nullopt, b.springback_uncertainty_deg(),
          b.decision());
    }
    add_shape_characteristics(r, add);
    if (r.has_deviation() && r.deviation().points() > 0) {
      const v1::Deviation& d = r.deviation();
      const std::optional<double> usl =
          d.tolerance_mm() > 0 ? std::optional<double>(d.tolerance_mm()) : std::nullopt;
      // deviation.uncertainty_mm and decision belong to the statistic the verdict compared.
      const bool by_max = r.settings().verdict().deviation_statistic() == v1::VerdictSettings::MAX;
      const auto judged = [&](bool is_max) {
        return is_max == by_max ? std::make_pair(d.uncertainty_mm(), d.decision())
                                : std::make_pair(0.0, v1::CONFORMITY_UNSPECIFIED);
      };
      add(r, "deviation max |d|", "mm", std::max(-d.min(), d.max()), std::nullopt, usl,
          judged(true).first, judged(true).second);
      add(r, "deviation p95", "mm", d.p95(), std::nullopt, usl, judged(false).first,
          judged(false).second);
    }
  }
  for (Characteristic& c : out) c.chart = control_chart(c.values, c.lsl, c.usl);
  std::stable_sort(out.begin(), out.end(), [](const Characteristic& a, const Characteristic& b) {
    if (a.chart.cpk.has_value() != b.chart.cpk.has_value()) return a.chart.cpk.has_value();
    if (a.chart.cpk && *a.chart.cpk != *b.chart.cpk) return *a.chart.cpk < *b.chart.cpk;
    return std::tie(a.part_id, a.name) < std::tie(b.part_id, b.name);
  });
  return out;
}

DecisionCounts decision_counts(const std::vector<v1::InspectionReport>& reports) {
  DecisionCounts counts;
  for (const v1::InspectionReport& r : reports) {
    switch (r.verdict().decision()) {
      case v1::Verdict::PASS:
        ++counts.pass;
        break;
      case v1::Verdict::FAIL:
        ++counts.fail;
        break;
      case v1::Verdict::UNDECIDED:
        ++counts.undecided;
        break;
      default:
        ++counts.none;
    }
  }
  return counts;
}

analysis::Expected<TrendInput> read_reports(const std::vector<std::string>& paths,
                                            unsigned threads) {
  std::vector<std::string> files;
  for (const std::string& path : paths) {
    std::error_code ec;
    if (fs::is_regular_file(path, ec)) {
      files.push_back(path);
      continue;
    }
    if (!fs::is_directory(path, ec)) {
      return analysis::fail(path + ": no such report file or directory");
    }
    for (auto it = fs::recursive_directory_iterator(path, ec);
         !ec && it != fs::recursive_directory_iterator(); it.increment(ec)) {
      const std::string name = it->path().filename().string();
      if (!name.empty() && name[0] == '.') {  // the report store's unfinished writes
        if (it->is_directory(ec)) it.disable_recursion_pending();
        continue;
      }
      if (it->path().extension() == ".pb" && it->is_regular_file(ec)) {
        files.push_back(it->path().string());
      }
    }
    if (ec) return analysis::fail(path + ": " + ec.message());
  }
  std::sort(files.begin(), files.end());
  files.erase(std::unique(files.begin(), files.end()), files.end());

  struct Parsed {
    v1::InspectionReport report;
    std::string error;
  };
  std::vector<Parsed> parsed(files.size());
  if (threads == 0) threads = std::max(1u, std::thread::hardware_concurrency());
  threads = static_cast<unsigned>(std::min<std::size_t>(threads, files.size() / 64 + 1));
  const auto work = [&](unsigned first) {
    // Parsed on an arena (one allocation block for the deformation field's many small
    // messages, freed at once), then only what the trend uses is kept.
    google::protobuf::Arena arena;
    for (std::size_t i = first; i < files.size(); i += threads) {
      auto bytes = analysis::read_file_bytes(files[i]);
      if (!bytes) {
        parsed[i].error = bytes.message();
        continue;
      }
      auto* full = google::protobuf::Arena::CreateMessage<v1::InspectionReport>(&arena);
      if (!full->ParseFromString(*bytes) || full->schema() != "springscan.report.v1") {
        parsed[i].error = files[i] + ": not an InspectionReport (springscan.report.v1)";
      } else {
        v1::InspectionReport& kept = parsed[i].report;
        kept.set_schema(full->schema());
        kept.set_created_utc(full->created_utc());
        kept.set_station(full->station());
        kept.set_job_id(full->job_id());
        kept.set_result_seq(full->result_seq());
        kept.set_result_code(full->result_code());
        kept.mutable_input()->set_part_id(full->input().part_id());
        kept.mutable_input()->set_part_serial(full->input().part_serial());  // msa type 3
        *kept.mutable_bends() = full->bends();
        *kept.mutable_segments() = full->segments();  // the shape characteristics
        *kept.mutable_settings()->mutable_verdict() = full->settings().verdict();  // limits
        if (full->has_deviation()) *kept.mutable_deviation() = full->deviation();
        if (full->has_verdict()) *kept.mutable_verdict() = full->verdict();
      }
      arena.Reset();
    }
  };
  std::vector<std::thread> pool;
  for (unsigned t = 1; t < threads; ++t) pool.emplace_back(work, t);
  work(0);
  for (auto& t : pool) t.join();

  TrendInput input;
  input.reports.reserve(files.size());
  for (Parsed& p : parsed) {
    if (p.error.empty()) {
      input.reports.push_back(std::move(p.report));
    } else {
      input.skipped.push_back(std::move(p.error));
    }
  }
  if (input.reports.empty()) {
    return analysis::fail(
        "no report.pb found in " + std::to_string(paths.size()) + " path(s)" +
        (input.skipped.empty() ? "" : " (first problem: " + input.skipped.front() + ")"));
  }
  std::stable_sort(input.reports.begin(), input.reports.end(),
                   [](const v1::InspectionReport& a, const v1::InspectionReport& b) {
                     return a.created_utc() < b.created_utc();
                   });
  return input;
}

}  // namespace springscan::report
