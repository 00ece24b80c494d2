#pragma once
// Gauge capability studies over inspection reports (`springscan msa`, docs/calibration.md): a
// type-1 study of one reference part measured again and again, and a type-3 study of several
// parts each measured several times (an automated gauge: no operator term). The characteristics
// and their names are `springscan trend`'s (report/trend.hpp: "bend 2 springback", "deviation
// p95", ...); the statistics are report/msa_stats.hpp's.
//
// Tolerance width T of a characteristic: from the reports, USL - LSL (2 x the angle tolerance
// for a springback), or USL alone for the one-sided deviation figures (|d| and p95 are never
// below 0, their natural lower limit); MsaSettings::tolerances overrides it by name.
//
// Thread safety: every function is pure.

#include <map>
#include <string>
#include <string_view>
#include <vector>

#include "analysis/core/expected.hpp"
#include "proto/springscan.pb.h"
#include "report/msa_stats.hpp"

namespace springscan::report {

struct MsaSettings {
  std::size_t min_type1_reports = 25;        ///< VDA 5: at least 25 (better 50) repeats
  std::size_t min_parts = 5;                 ///< type 3: parts
  std::size_t min_trials = 2;                ///< type 3: trials per part
  std::map<std::string, double> tolerances;  ///< T by characteristic name, over the reports'
  std::vector<std::string> only;             ///< study only these names (empty: see below)
  MsaLimits limits;                          ///< the verdicts' limits
};

/// The type-1 study of `reports` (time order, one part id) for every characteristic named in
/// `references` (name -> reference value), or those of settings.only. Errors (code
/// kInvalidInput, nothing partial): fewer than min_type1_reports reports, mixed part ids, a
/// characteristic missing in some report or absent from `references`.
analysis::Expected<v1::MsaType1Study> type1_study(const std::vector<v1::InspectionReport>& reports,
                                                  const std::map<std::string, double>& references,
                                                  const MsaSettings& settings = {});

/// The type-3 study of `reports` (time order, one part id), grouped by input.part_serial, for
/// every characteristic the reports have (or settings.only). Errors: a report without a part
/// serial, mixed part ids, fewer than min_parts parts or min_trials trials, an unbalanced study
/// (parts measured a different number of times), a characteristic missing in some report.
analysis::Expected<v1::MsaType3Study> type3_study(const std::vector<v1::InspectionReport>& reports,
                                                  const MsaSettings& settings = {});

/// REF.json: one JSON object mapping a characteristic name to its reference value,
/// {"bend 1 springback": 0.42, ...}.
analysis::Expected<std::map<std::string, double>> parse_references(std::string_view json);

/// One `--tolerance NAME=T` argument (T > 0); the name may hold spaces and '='.
analysis::Expected<std::pair<std::string, double>> parse_tolerance(const std::string& text);

/// A study as JSON (protobuf's JSON mapping, proto field names, every field printed).
analysis::Expected<std::string> msa_to_json(const google::protobuf::Message& study);

}  // namespace springscan::report
