#pragma once
// The analysis the daemon runs with (the part's cached CAD model + run_inspection). Kept out of
// main() so it fits a page. The scanner comes from drivers::make_scanner
// (drivers/scanner_proto.hpp).

#include <memory>
#include <string>
#include <vector>

#include "daemon/config.hpp"
#include "daemon/job_runner.hpp"
#include "daemon/log.hpp"

namespace springscan::daemon {

/// The analysis for the part catalogue: looks the part id up, loads its model (cached), runs
/// the pipeline with the part's settings.
AnalyzeFn make_analysis(const std::vector<PartEntry>& parts, const std::string& model_cache_dir,
                        Log& log);

}  // namespace springscan::daemon
