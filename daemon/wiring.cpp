#include "daemon/wiring.hpp"

#include <map>

namespace springscan::daemon {

namespace {

/// The scanner while no USB driver is linked into this build: always absent, so READY stays 0
/// and every trigger is refused with REJECT_CODE 5 (scanner offline). Replaced by the libusb
/// driver (issue 7) in make_scanner when it lands.
class AbsentScanner : public drivers::Scanner {
 public:
  analysis::Expected<drivers::DeviceInfo> identify() override {
    return analysis::fail("no scanner driver in this build of springscand");
  }
  analysis::Expected<analysis::PointCloud> scan(const drivers::ScanProgress&) override {
    return analysis::fail("no scanner driver in this build of springscand");
  }
  bool online() const override { return false; }
};

}  // namespace

std::unique_ptr<drivers::Scanner> make_scanner(const v1::ScannerConfig& config, Log& log) {
  (void)config;
  log.warning("this build has no scanner driver: the station will report SCANNER_ONLINE = 0");
  return std::make_unique<AbsentScanner>();
}

AnalyzeFn make_analysis(const std::vector<PartEntry>& parts, const std::string& model_cache_dir,
                        Log& log) {
  (void)model_cache_dir;
  (void)log;
  std::map<std::uint16_t, PartEntry> catalogue;
  for (const PartEntry& p : parts) catalogue[p.part_id] = p;
  return [catalogue](std::uint16_t part_id, const analysis::PointCloud&)
             -> analysis::Expected<analysis::InspectionOutcome> {
    const auto found = catalogue.find(part_id);
    if (found == catalogue.end()) {
      return analysis::fail("part " + std::to_string(part_id) + " is not in the catalogue");
    }
    return analysis::fail("the analysis pipeline is not linked into this build (part " +
                          found->second.cad_file + ")");
  };
}

}  // namespace springscan::daemon
