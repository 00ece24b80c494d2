#include "daemon/wiring.hpp"

#include <map>
#include <memory>
#include <mutex>

#include "analysis/cad/model.hpp"
#include "analysis/inspection/pipeline.hpp"
#include "analysis/messages/cad_model_proto.hpp"

namespace springscan::daemon {

namespace {

/// The CAD model of each part, loaded on first use (on the runner's thread) and kept: import,
/// even samples with exact normals, the segmentation into flanges and bends, and the exact
/// point-to-surface distance (DESIGN.md stages 1-2). Models go through the on-disk cache
/// (analysis/cad/model.hpp), so a restarted daemon skips IGES/STEP parsing and healing.
class PartModels {
 public:
  PartModels(const std::vector<PartEntry>& parts, std::string cache_dir, Log& log)
      : log_(log), cache_dir_(std::move(cache_dir)) {
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
    auto settings = analysis::from_proto(part.settings.cad_model());
    if (!settings) return settings.error().prepend(kPartModelErrorPrefix);
    auto model = load(part, *settings);
    if (!model) return model.error().prepend(kPartModelErrorPrefix);
    const auto& segmentation = (*model)->segmentation;
    log_.info("part " + std::to_string(part.part_id) + " (" + part.name + "): CAD model " +
              part.cad_file + " ready: " + std::to_string((*model)->face_count) + " faces, " +
              std::to_string(segmentation.flanges.size()) + " flanges, " +
              std::to_string(segmentation.bends.size()) + " bends");
    models_[part.part_id] = *model;
    return *model;
  }

 private:
  analysis::Expected<std::shared_ptr<const analysis::PartModel>> load(
      const PartEntry& part, const analysis::CadModelSettings& settings) {
    if (cache_dir_.empty()) {
      auto model = analysis::load_part_model(part.cad_file, settings);
      if (!model) return model.error();
      return std::make_shared<const analysis::PartModel>(std::move(*model));
    }
    auto loaded = analysis::load_part_model_cached(part.cad_file, cache_dir_, settings);
    if (!loaded) return loaded.error();
    if (!loaded->cache_error.empty())
      log_.warning("model cache: " + loaded->cache_error + " (the model itself is fine)");
    log_.info("part " + std::to_string(part.part_id) + ": model cache " +
              (loaded->cache_hit ? "hit " : "miss, written to ") + loaded->cache_file);
    return std::make_shared<const analysis::PartModel>(std::move(loaded->model));
  }

  Log& log_;
  std::string cache_dir_;
  std::map<std::uint16_t, PartEntry> parts_;
  std::mutex mutex_;
  std::map<std::uint16_t, std::shared_ptr<const analysis::PartModel>> models_;
};

}  // namespace

AnalyzeFn make_analysis(const std::vector<PartEntry>& parts, const std::string& model_cache_dir,
                        Log& log) {
  auto models = std::make_shared<PartModels>(parts, model_cache_dir, log);
  return [models](
             std::uint16_t part_id,
             const analysis::PointCloud& scan) -> analysis::Expected<analysis::InspectionOutcome> {
    const PartEntry* part = models->entry(part_id);
    if (part == nullptr) {
      return analysis::fail(analysis::ErrorCode::kNotFound, std::string(kPartModelErrorPrefix) +
                                                                "part " + std::to_string(part_id) +
                                                                " is not in the catalogue");
    }
    auto model = models->get(*part);
    if (!model) return model.error();
    auto outcome = analysis::run_inspection(**model, scan, part->settings);
    if (outcome) outcome->report.mutable_input()->set_cad_file(part->cad_file);
    return outcome;
  };
}

}  // namespace springscan::daemon
