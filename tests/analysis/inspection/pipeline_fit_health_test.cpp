// The verdict's fit-health rule on a large production part: a perfectly made part, scanned with
// scanner noise, must pass whatever the spacing of the model samples.
#include <gtest/gtest.h>

#include <random>

#include "analysis/cad/import.hpp"
#include "analysis/cad/model.hpp"
#include "analysis/cad/sampling.hpp"
#include "analysis/inspection/pipeline.hpp"
#include "tests/analysis/cad_test_util.hpp"

namespace springscan::analysis {
namespace {

TEST(PipelineFitHealth, ALargePerfectPartPasses) {
  const std::string path = testing::shared_cad("openamr-MMP.00.00.00.001_Front_panel.step");
  auto model = load_part_model(path);
  ASSERT_TRUE(model.ok()) << model.message();
  auto shape = load_cad(path);
  ASSERT_TRUE(shape.ok()) << shape.message();
  // An independent sampling of the same surface (another seed), with 0.01 mm noise: the part
  // exactly as designed, scanned all round, in the CAD frame.
  auto scan = sample_cad(*shape, {.sample_count = 60000, .seed = 77});
  ASSERT_TRUE(scan.ok()) << scan.message();
  std::mt19937 rng(5);
  std::normal_distribution<double> noise(0.0, 0.01);
  for (std::size_t i = 0; i < scan->size(); ++i) scan->points[i] += noise(rng) * scan->normals[i];
  // The normals stay: scanned all round, the part has no one viewpoint that normals estimated
  // from the points could be turned towards, and on a solid the fit pairs by the side a point
  // faces (registration/facing.hpp).
  scan->face_ids.clear();

  // The scan is in the CAD frame: ICP starts there. The alignment of near-symmetric parts from
  // any pose is the global fit's business (its own tests); this test is about the health rule.
  v1::AnalysisSettings settings;
  settings.mutable_registration()->set_pca_initial_alignment(false);
  auto outcome = run_inspection(*model, *scan, settings);
  ASSERT_TRUE(outcome.ok()) << outcome.message();
  const v1::InspectionReport& r = outcome->report;
  // The nearest-sample distance is dominated by the sample spacing on a 385 x 165 mm part
  // (1.35 mm here; the old rule failed the part on it)...
  EXPECT_GT(r.global_fit().rms_final(), 1.0);
  // ... the residual to the surface is near the noise, and the good part passes. (The fit
  // itself ends within 0.06 degrees and 0.03 mm of the true pose; its accuracy on thick
  // sheets is the alignment's business.)
  EXPECT_LT(r.global_fit().rms_residual(), 0.1);
  EXPECT_LT(r.deviation().rms(), 0.1);
  EXPECT_TRUE(r.verdict().pass());
  for (const auto& reason : r.verdict().reasons())
    EXPECT_EQ(reason.find("global fit"), std::string::npos) << reason;
}

}  // namespace
}  // namespace springscan::analysis
