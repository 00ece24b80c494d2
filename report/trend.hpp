#pragma once
// Statistical process control over many reports (`springscan trend`, docs/plant-integration.md
// "Trends"): the characteristics of each part (each bend's springback, the surface deviation's
// max |d| and p95) as individuals in report order, with the individuals / moving-range (I-MR)
// control limits, Cp and Cpk, and the Western Electric run rules.
//
// Individuals chart (Montgomery, Introduction to Statistical Quality Control, section 6.4):
//   MR_i = |x_i - x_{i-1}|, MR-bar their mean, sigma = MR-bar / d2 with d2 = 1.128 (n = 2);
//   centre X-bar, limits X-bar +- 2.66 MR-bar (= 3 sigma); MR chart limit D4 MR-bar = 3.267 MR-bar.
//   Cp = (USL - LSL) / (6 sigma), Cpk = min(USL - X-bar, X-bar - LSL) / (3 sigma), with the
//   short-term sigma; with one limit only Cp is undefined and Cpk uses that side.
// Each value keeps its expanded uncertainty U (k = 2) and its decision (issue 41) where the
// report has them; the page shows value +- U and counts the UNDECIDED values and parts.
// Western Electric rules (Western Electric Statistical Quality Control Handbook, 1956), flagged
// on every point that takes part in the breach:
//   1: a point beyond 3 sigma;  2: 2 of 3 consecutive points beyond 2 sigma on the same side;
//   3: 4 of 5 consecutive points beyond 1 sigma on the same side;
//   4: 8 consecutive points on the same side of the centre line.

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "analysis/core/expected.hpp"
#include "proto/springscan.pb.h"

namespace springscan::report {

/// Bits of ControlChart::rules, one per Western Electric rule.
enum WesternElectricRule : std::uint8_t {
  kRuleBeyond3Sigma = 1 << 0,
  kRule2Of3Beyond2Sigma = 1 << 1,
  kRule4Of5Beyond1Sigma = 1 << 2,
  kRule8OnOneSide = 1 << 3,
};

struct ControlChart {
  std::size_t n = 0;
  double mean = 0.0;                 ///< X-bar, the centre line
  double mr_bar = 0.0;               ///< mean moving range (0 with fewer than 2 points)
  double sigma = 0.0;                ///< MR-bar / 1.128
  double ucl = 0.0;                  ///< X-bar + 2.66 MR-bar
  double lcl = 0.0;                  ///< X-bar - 2.66 MR-bar
  double mr_ucl = 0.0;               ///< 3.267 MR-bar
  std::optional<double> cp;          ///< both tolerance limits and sigma > 0
  std::optional<double> cpk;         ///< a tolerance limit and sigma > 0
  std::vector<double> moving_range;  ///< MR_i for i >= 1 (size n - 1)
  std::vector<std::uint8_t> rules;   ///< per point: WesternElectricRule bits it breaks
  std::size_t points_flagged = 0;    ///< points with any rule bit
};

/// The I-MR chart of `values` (in time order) against the optional tolerance limits.
ControlChart control_chart(const std::vector<double>& values, std::optional<double> lsl,
                           std::optional<double> usl);

/// One characteristic of one part over the reports, in report order.
struct Characteristic {
  std::string part_id;
  std::string name;  ///< "bend 2 springback", "deviation max |d|", "deviation p95"
  std::string unit;  ///< "deg", "mm" or "deg/100 mm"
  std::optional<double> lsl, usl;
  std::vector<double> values;
  std::vector<std::string> labels;      ///< per value: which report ("seq 12, job 5, 2026-...")
  ControlChart chart;                   ///< filled by collect_characteristics
  std::vector<double> uncertainties{};  ///< per value: its U (k = 2); 0 where the report has none
  std::size_t undecided = 0;            ///< values the report's decision rule left UNDECIDED
  std::size_t nonconforming = 0;        ///< values it found NONCONFORMING
};

/// The part decisions of many reports (verdict.decision): PASS, FAIL, UNDECIDED, and the
/// results without one (a failed scan, a report from before decisions).
struct DecisionCounts {
  std::size_t pass = 0, fail = 0, undecided = 0, none = 0;
};
DecisionCounts decision_counts(const std::vector<v1::InspectionReport>& reports);

/// The characteristics of `reports` (given in time order), per part id; a bend counts only
/// where it was measured. Tolerance limits: +-angle_tolerance_deg for springback (nominal 0),
/// and tolerance_mm above for the deviation figures (one-sided). Sorted by Cpk, lowest first
/// (those without a Cpk last).
std::vector<Characteristic> collect_characteristics(
    const std::vector<v1::InspectionReport>& reports);

struct TrendInput {
  /// Ordered by created_utc, then path. Only what the trend uses is kept: schema, created_utc,
  /// station, job_id, result_seq, result_code, input.part_id and part_serial, bends, segments,
  /// deviation, verdict, settings.verdict (the shape limits).
  std::vector<v1::InspectionReport> reports;
  std::vector<std::string> skipped;  ///< "path: reason" for files that were not reports
};

/// Reads every report.pb under `paths` (a report store, a folder of report.pb files, or single
/// files; folders are searched recursively for *.pb) on up to `threads` threads (0: all cores).
/// An unreadable file is skipped and named; no report at all is an error.
analysis::Expected<TrendInput> read_reports(const std::vector<std::string>& paths,
                                            unsigned threads = 0);

}  // namespace springscan::report
