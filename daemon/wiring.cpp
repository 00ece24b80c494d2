#include "daemon/wiring.hpp"

#include <map>
#include <memory>
#include <mutex>

#include "analysis/cad_distance.hpp"
#include "analysis/cad_import.hpp"
#include "analysis/cad_sampling.hpp"
#include "analysis/pipeline.hpp"
#include "drivers/laser_scanner.hpp"
#include "drivers/protocol.hpp"
#include "drivers/tactile_scanner.hpp"

namespace springscan::daemon {

namespace {

drivers::LinkSettings link_settings(const v1::ScannerConfig& config, std::uint16_t default_pid) {
  drivers::LinkSettings link;
  link.usb.vendor_id = config.has_vendor_id() ? static_cast<std::uint16_t>(config.vendor_id())
                                              : drivers::protocol::kVendorId;
  link.usb.product_id =
      config.has_product_id() ? static_cast<std::uint16_t>(config.product_id()) : default_pid;
  link.usb.serial = config.serial();
  if (config.has_timeout_s()) link.data_timeout_ms = static_cast<int>(config.timeout_s() * 1000);
  return link;
}

/// The CAD model of each part, loaded on first use (on the runner's thread) and kept. The
/// model is the CAD import, even surface samples with exact normals, and the exact
/// point-to-surface distance (DESIGN.md stages 1-2).
class PartModels {
 public:
  PartModels(const std::vector<PartEntry>& parts, Log& log) : log_(log) {
    for (const PartEntry& p : parts) parts_[p.part_id] = p;
  }

  const PartEntry* entry(std::uint16_t part_id) const {
    const auto found = parts_.find(part_id);
    return found == parts_.end() ? nullptr : &found->second;
  }

  analysis::Expected<std::shared_ptr<const analysis::PartModel>> get(const PartEntry& part) {
    std::lock_guard lock(mutex_);
    if (const auto cached = models_.find(part.part_id); cached != models_.end()) {
      return cached->second;
    }
    const v1::ModelSettings& m = part.settings.model();
    analysis::CadImportSettings import;
    if (m.has_linear_deflection_mm()) import.linear_deflection_mm = m.linear_deflection_mm();
    if (m.has_angular_deflection_deg()) import.angular_deflection_deg = m.angular_deflection_deg();
    auto shape = analysis::load_cad(part.cad_file, import);
    if (!shape) return analysis::fail(std::string(kPartModelErrorPrefix) + shape.message());
    analysis::CadSamplingSettings sampling;
    if (m.has_sample_count()) sampling.sample_count = m.sample_count();
    auto samples = analysis::sample_cad(*shape, sampling);
    if (!samples) return analysis::fail(std::string(kPartModelErrorPrefix) + samples.message());
    auto model = std::make_shared<analysis::PartModel>();
    model->samples = std::move(*samples);
    model->face_count = shape->face_count();
    model->distance = analysis::make_cad_distance(*shape);
    log_.info("part " + std::to_string(part.part_id) + " (" + part.name + "): CAD model " +
              part.cad_file + " loaded: " + analysis::summary(shape->report()));
    models_[part.part_id] = model;
    return std::shared_ptr<const analysis::PartModel>(model);
  }

 private:
  Log& log_;
  std::map<std::uint16_t, PartEntry> parts_;
  std::mutex mutex_;
  std::map<std::uint16_t, std::shared_ptr<const analysis::PartModel>> models_;
};

}  // namespace

std::unique_ptr<drivers::Scanner> make_scanner(const v1::ScannerConfig& config, Log& log) {
  if (config.kind() == v1::ScannerConfig::TACTILE_PROBE) {
    drivers::TactileScannerSettings settings;
    settings.link = link_settings(config, drivers::protocol::kProductIdTactile);
    log.info("scanner: tactile probe, USB " + std::to_string(settings.link.usb.vendor_id) + ":" +
             std::to_string(settings.link.usb.product_id));
    return std::make_unique<drivers::TactileProbeScanner>(settings);
  }
  drivers::LaserScannerSettings settings;
  settings.link = link_settings(config, drivers::protocol::kProductIdLaser);
  log.info("scanner: laser line, USB " + std::to_string(settings.link.usb.vendor_id) + ":" +
           std::to_string(settings.link.usb.product_id));
  return std::make_unique<drivers::LaserLineScanner>(settings);
}

AnalyzeFn make_analysis(const std::vector<PartEntry>& parts, const std::string& model_cache_dir,
                        Log& log) {
  (void)model_cache_dir;  // the in-memory cache covers a daemon's lifetime
  auto models = std::make_shared<PartModels>(parts, log);
  return [models](std::uint16_t part_id, const analysis::PointCloud& scan)
             -> analysis::Expected<analysis::InspectionOutcome> {
    const PartEntry* part = models->entry(part_id);
    if (part == nullptr) {
      return analysis::fail(std::string(kPartModelErrorPrefix) + "part " +
                            std::to_string(part_id) + " is not in the catalogue");
    }
    auto model = models->get(*part);
    if (!model) return analysis::fail(model.message());
    auto outcome = analysis::run_inspection(**model, scan, part->settings);
    if (outcome) outcome->report.mutable_input()->set_cad_file(part->cad_file);
    return outcome;
  };
}

}  // namespace springscan::daemon
