#pragma once
// The production parts of ../shared/data/cad (SOURCES.md) loaded once per test process: the
// shape (tessellation, face adjacency) and its PartModel (samples, segmentation).

#include <gtest/gtest.h>

#include <map>
#include <string>
#include <vector>

#include "simulators/parts/produced_part.hpp"
#include "tests/analysis/cad_test_util.hpp"

namespace springscan::parts::testing {

using LoadedPart = CadPart;

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
  auto part = load_cad_part(analysis::testing::shared_cad(name));
  EXPECT_TRUE(part) << name << ": " << part.message();
  return cache.emplace(name, part ? std::move(*part) : CadPart{}).first->second;
}

}  // namespace springscan::parts::testing
