#pragma once
// The production parts of ../shared/data/cad (SOURCES.md) loaded once per test process: the
// shape (tessellation, face adjacency) and its PartModel (samples, segmentation).

#include <gtest/gtest.h>

#include <map>
#include <string>
#include <vector>

#include "analysis/cad/import.hpp"
#include "analysis/cad/sampling.hpp"
#include "analysis/cad/segmentation.hpp"
#include "analysis/core/part_model.hpp"
#include "tests/analysis/cad_test_util.hpp"

namespace springscan::parts::testing {

struct LoadedPart {
  analysis::CadShape shape;
  analysis::PartModel model;
};

inline const std::vector<std::string>& production_parts() {
  static const std::vector<std::string> names = {
      "openamr-MMP.03.00.00.003_Motor_bracket.step", "openamr-MMP.01.00.00.002_Cover_flange.step",
      "openamr-MMP.00.00.00.003_Side_panel.step", "openamr-MMP.00.00.00.001_Front_panel.step",
      "nema-17-bracket.step"};
  return names;
}

/// The part `name` of the shared CAD folder, loaded on first use (fails the test if it cannot).
inline const LoadedPart& loaded_part(const std::string& name) {
  static std::map<std::string, LoadedPart> cache;
  auto it = cache.find(name);
  if (it != cache.end()) return it->second;
  LoadedPart part;
  auto shape = analysis::load_cad(analysis::testing::shared_cad(name));
  EXPECT_TRUE(shape) << name << ": " << shape.message();
  if (shape) {
    part.shape = *shape;
    auto samples = analysis::sample_cad(part.shape);
    EXPECT_TRUE(samples) << samples.message();
    if (samples) part.model.samples = std::move(*samples);
    part.model.segmentation = analysis::segment_cad(part.shape);
    part.model.face_count = part.shape.face_count();
  }
  return cache.emplace(name, std::move(part)).first->second;
}

}  // namespace springscan::parts::testing
