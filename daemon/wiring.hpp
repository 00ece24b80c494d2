#pragma once
// The real pieces the daemon runs with: the scanner driver named by the config, and the
// analysis (the part's cached CAD model + run_inspection). Kept out of main() so it fits a page.

#include <memory>
#include <string>
#include <vector>

#include "daemon/config.hpp"
#include "daemon/job_runner.hpp"
#include "daemon/log.hpp"
#include "drivers/scanner.hpp"

namespace springscan::daemon {

/// The scanner driver for `config`. Never null; a scanner that cannot be opened reports
/// online() == false and the runner keeps trying.
std::unique_ptr<drivers::Scanner> make_scanner(const v1::ScannerConfig& config, Log& log);

/// The analysis for the part catalogue: looks the part id up, loads its model (cached), runs
/// the pipeline with the part's settings.
AnalyzeFn make_analysis(const std::vector<PartEntry>& parts, const std::string& model_cache_dir,
                        Log& log);

}  // namespace springscan::daemon
