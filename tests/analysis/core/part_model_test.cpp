#include "analysis/core/part_model.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <thread>
#include <vector>

namespace springscan::analysis {
namespace {

PointCloud cloud_of(double x) {
  PointCloud c;
  c.points = {Vec3(x, 0.0, 0.0)};
  return c;
}

// The boundary's tessellation sample is built once per model and count (issue 37): the same
// cloud for every call with a key, a build per key, none in a copy of the model.
TEST(DerivedSamples, BuiltOncePerKeyAndNotSharedByACopy) {
  PartModel model;
  int builds = 0;
  const auto a = model.tessellation_samples.get(10, [&] { return ++builds, cloud_of(1.0); });
  const auto b = model.tessellation_samples.get(10, [&] { return ++builds, cloud_of(2.0); });
  EXPECT_EQ(a.get(), b.get());
  EXPECT_EQ(builds, 1);
  EXPECT_EQ(b->points[0].x(), 1.0);
  const auto c = model.tessellation_samples.get(20, [&] { return ++builds, cloud_of(3.0); });
  EXPECT_EQ(builds, 2);
  EXPECT_EQ(c->points[0].x(), 3.0);

  PartModel copy = model;  // its mesh may be changed: it derives its own
  const auto d = copy.tessellation_samples.get(10, [&] { return ++builds, cloud_of(4.0); });
  EXPECT_EQ(builds, 3);
  EXPECT_EQ(d->points[0].x(), 4.0);
  copy = model;
  EXPECT_EQ(
      copy.tessellation_samples.get(10, [&] { return ++builds, cloud_of(5.0); })->points[0].x(),
      5.0);
  EXPECT_EQ(a->points[0].x(), 1.0);  // the original's is kept
}

TEST(DerivedSamples, ConcurrentCallersShareOneBuild) {
  PartModel model;
  std::atomic<int> builds{0};
  std::vector<const PointCloud*> seen(4, nullptr);
  std::vector<std::thread> threads;
  for (std::size_t t = 0; t < seen.size(); ++t)
    threads.emplace_back([&, t] {
      seen[t] = model.tessellation_samples.get(7, [&] { return ++builds, cloud_of(7.0); }).get();
    });
  for (auto& t : threads) t.join();
  EXPECT_EQ(builds.load(), 1);
  for (const PointCloud* p : seen) EXPECT_EQ(p, seen[0]);
}

}  // namespace
}  // namespace springscan::analysis
