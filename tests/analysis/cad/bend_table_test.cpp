// The bends of the shared production parts against a truth that is not springscan's: the bend
// table of ../shared/data/cad/SOURCES.md, measured by whoever put the files there (OpenCASCADE,
// pairs of coaxial partial cylinders). The table is parsed here, at run time, so that a wrong
// segmentation (a bend missed, split, merged or mis-measured) fails, and so does the produced
// part of the simulator, which builds its bends from the same segmentation: everything the
// production-part tests call "truth" starts from what this test checks independently.
#include <gtest/gtest.h>

#include <algorithm>
#include <fstream>
#include <map>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "analysis/cad/segmentation.hpp"
#include "simulators/parts/produced_part.hpp"
#include "tests/analysis/cad_test_util.hpp"
#include "tests/analysis/under_sanitizer.hpp"
#include "tests/simulators/parts/production_parts.hpp"

namespace springscan::analysis {
namespace {

/// One row of SOURCES.md's production-part table.
struct TableRow {
  std::string file;
  double thickness_mm = 0.0;
  double inner_radius_mm = 0.0;
  std::vector<double> bend_angles_deg;  ///< every bend, sorted
  std::vector<double> hem_radii_mm;     ///< per closed hem, its own inner radius
};

std::vector<std::string> split(const std::string& line, char by) {
  std::vector<std::string> out;
  std::stringstream in(line);
  for (std::string cell; std::getline(in, cell, by);) out.push_back(cell);
  return out;
}

// "90 x 12, 45 x 4" or "132 x 1, 122.74 x 2, closed hem 180 x 3 (Ri 0.05)".
void parse_bends(const std::string& cell, TableRow& row) {
  static const std::regex group(R"((closed hem )?([0-9.]+) x ([0-9]+)( \(Ri ([0-9.]+)\))?)");
  for (std::sregex_iterator it(cell.begin(), cell.end(), group), end; it != end; ++it) {
    const double angle = std::stod((*it)[2]);
    const int count = std::stoi((*it)[3]);
    for (int k = 0; k < count; ++k) {
      row.bend_angles_deg.push_back(angle);
      if ((*it)[1].matched) row.hem_radii_mm.push_back(std::stod((*it)[5]));
    }
  }
  std::sort(row.bend_angles_deg.begin(), row.bend_angles_deg.end());
}

/// The rows of the "Production sheet-metal parts" table: | File | Part | t | Ri | Bends | ...
std::vector<TableRow> read_bend_table() {
  std::ifstream in(testing::shared_cad("SOURCES.md"));
  std::vector<TableRow> rows;
  for (std::string line; std::getline(in, line);) {
    if (line.rfind("| openamr-", 0) != 0) continue;
    const auto cells = split(line, '|');  // cells[0] is empty: the line starts with '|'
    if (cells.size() < 6) continue;
    TableRow row;
    row.file = cells[1].substr(1, cells[1].find(' ', 1) - 1);
    row.thickness_mm = std::stod(cells[3]);
    row.inner_radius_mm = std::stod(cells[4]);
    parse_bends(cells[5], row);
    rows.push_back(row);
  }
  return rows;
}

TEST(BendTable, SourcesListsTheFourProductionParts) {
  const auto rows = read_bend_table();
  ASSERT_EQ(rows.size(), 4u) << "SOURCES.md's production table changed shape";
  std::map<std::string, std::size_t> bends;
  for (const auto& r : rows) bends[r.file] = r.bend_angles_deg.size();
  EXPECT_EQ(bends["openamr-MMP.03.00.00.003_Motor_bracket.step"], 4u);
  EXPECT_EQ(bends["openamr-MMP.01.00.00.002_Cover_flange.step"], 8u);
  EXPECT_EQ(bends["openamr-MMP.00.00.00.003_Side_panel.step"], 16u);
  EXPECT_EQ(bends["openamr-MMP.00.00.00.001_Front_panel.step"], 4u);
}

class BendTablePart : public ::testing::TestWithParam<int> {
 protected:
  // Under the sanitizers (5-15x slower) the motor bracket alone: they look for memory errors.
  void SetUp() override {
    if (testing::kUnderSanitizer && GetParam() != 0) GTEST_SKIP() << "release suite only";
  }
};

// Every bend of the table is found once, with its angle and inner radius, and nothing else is.
TEST_P(BendTablePart, SegmentationMatchesTheTable) {
  const TableRow row = read_bend_table().at(static_cast<std::size_t>(GetParam()));
  const auto& part = parts::testing::loaded_part(row.file);
  const auto& bends = part.model.segmentation.bends;
  std::vector<double> angles;
  for (const Bend& b : bends) angles.push_back(b.nominal_angle_deg);
  std::sort(angles.begin(), angles.end());
  ASSERT_EQ(angles.size(), row.bend_angles_deg.size()) << row.file;
  for (std::size_t k = 0; k < angles.size(); ++k)
    EXPECT_NEAR(angles[k], row.bend_angles_deg[k], 0.01) << row.file << " bend " << k;
  std::size_t hems = 0;
  for (const Bend& b : bends) {
    const bool hem = b.nominal_angle_deg > 179.0;
    const double radius = hem ? row.hem_radii_mm.at(hems++) : row.inner_radius_mm;
    EXPECT_NEAR(b.radius_mm, radius, 0.01) << row.file << " bend " << b.id;
    EXPECT_NE(b.flange_a, b.flange_b) << row.file << " bend " << b.id;
  }
  EXPECT_EQ(hems, row.hem_radii_mm.size()) << row.file;
  // Every flange of a bend has the table's sheet thickness (a solid: both skins found).
  for (const Bend& b : bends)
    for (int id : {b.flange_a, b.flange_b}) {
      const auto& flanges = part.model.segmentation.flanges;
      const auto it =
          std::find_if(flanges.begin(), flanges.end(), [&](const Flange& f) { return f.id == id; });
      ASSERT_NE(it, flanges.end()) << row.file << " bend " << b.id;
      EXPECT_NEAR(it->thickness_mm, row.thickness_mm, 0.01) << row.file << " flange " << id;
    }
}

// The simulator's produced part takes its bends from the segmentation: with no springback its
// bend truths carry the table's angles, and every bend opens by what is asked but the hems.
TEST_P(BendTablePart, ProducedPartCarriesTheTable) {
  const TableRow row = read_bend_table().at(static_cast<std::size_t>(GetParam()));
  const auto& part = parts::testing::loaded_part(row.file);
  std::vector<double> springback(part.model.segmentation.bends.size(), 1.0);
  const auto produced = parts::make_produced_part(part.model, part.shape, springback);
  ASSERT_TRUE(produced) << produced.message();
  std::vector<double> nominal;
  for (const parts::BendTruth& b : produced->bends) {
    nominal.push_back(b.nominal_angle_deg);
    if (b.closes_cycle) continue;
    EXPECT_NEAR(b.springback_deg, b.hem ? 0.0 : 1.0, 1e-12) << row.file << " bend " << b.bend_id;
    EXPECT_NEAR(b.produced_angle_deg, b.nominal_angle_deg - b.springback_deg, 1e-9);
  }
  std::sort(nominal.begin(), nominal.end());
  ASSERT_EQ(nominal.size(), row.bend_angles_deg.size());
  for (std::size_t k = 0; k < nominal.size(); ++k)
    EXPECT_NEAR(nominal[k], row.bend_angles_deg[k], 0.01) << row.file;
}

std::string row_name(const ::testing::TestParamInfo<int>& info) {
  static const char* names[] = {"MotorBracket", "CoverFlange", "SidePanel", "FrontPanel"};
  return names[info.param];
}

// The table's order (SOURCES.md): motor bracket, cover flange, side panel, front panel.
INSTANTIATE_TEST_SUITE_P(Openamr, BendTablePart, ::testing::Range(0, 4), row_name);

}  // namespace
}  // namespace springscan::analysis
