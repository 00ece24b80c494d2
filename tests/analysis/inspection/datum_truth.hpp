#pragma once
// The truth side of the datum tests (docs/alignment.md "Own parts", "Production parts"): how far
// a result frame is from the constructed one, and the frame's noise floor from what the report
// says it measured.

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <utility>
#include <vector>

#include "analysis/registration/datum.hpp"
#include "proto/springscan.pb.h"
#include "simulators/parts/laser_scan.hpp"

namespace springscan::analysis::testing {

// Three pad points spread over `clear` (at least three candidates): the farthest from their
// centre, the farthest from that one, and the one that makes the largest triangle with both.
inline std::vector<Vec3> three_spread_points(const std::vector<Vec3>& clear) {
  Vec3 centre = Vec3::Zero();
  for (const Vec3& p : clear) centre += p / static_cast<double>(clear.size());
  const auto farthest = [&](auto score) {
    return *std::max_element(clear.begin(), clear.end(),
                             [&](const Vec3& a, const Vec3& b) { return score(a) < score(b); });
  };
  const Vec3 a = farthest([&](const Vec3& p) { return (p - centre).norm(); });
  const Vec3 b = farthest([&](const Vec3& p) { return (p - a).norm(); });
  const Vec3 c = farthest([&](const Vec3& p) { return (p - a).cross(p - b).norm(); });
  return {a, b, c};
}

// The part scanned in one laser pass per view direction (`directions` in the part's frame,
// turned by R as the part lies), pass k with seed `seed` x 10 + k, the passes merged with their
// normals. False (and a test failure) when a pass fails.
inline bool scan_in_passes(const parts::ProducedPart& part, parts::LaserScanSettings ls,
                           const Mat3& R, const std::vector<Vec3>& directions, std::uint64_t seed,
                           PointCloud& scan) {
  for (std::size_t k = 0; k < directions.size(); ++k) {
    ls.view_direction = R * directions[k];
    ls.seed = seed * 10 + k;
    auto pass = parts::laser_scan(part, ls);
    EXPECT_TRUE(pass) << pass.message();
    if (!pass) return false;
    scan.points.insert(scan.points.end(), pass->cloud.points.begin(), pass->cloud.points.end());
    scan.normals.insert(scan.normals.end(), pass->cloud.normals.begin(), pass->cloud.normals.end());
  }
  return true;
}

// The frame's noise floor from the report: each datum's fixed directions with the standard error
// of its measurement (a pad's plane at its centre: rms / sqrt(n); a hole's centre: rms x
// sqrt(2 / n); a slot's mid-plane: rms / sqrt(n / 2)), propagated through the weighted 3-2-1
// solve at the nominal points; the largest 1-sigma move over `points`, and the rotation's.
inline std::pair<double, double> datum_noise_floor(const v1::Alignment& a,
                                                   const std::vector<Datum>& datums,
                                                   const std::vector<Vec3>& points) {
  Vec3 o = Vec3::Zero();
  for (const Datum& d : datums) o += d.point / static_cast<double>(datums.size());
  Eigen::Matrix<double, 6, 6> info = Eigen::Matrix<double, 6, 6>::Zero();
  for (std::size_t k = 0; k < datums.size(); ++k) {
    const Datum& d = datums[k];
    const auto n =
        static_cast<double>(std::max<std::int64_t>(a.datums(static_cast<int>(k)).points(), 1));
    const double rms = std::max(a.datums(static_cast<int>(k)).fit_rms_mm(), 1e-3);
    double sigma = rms / std::sqrt(n);
    std::vector<Vec3> dirs = {d.normal};
    if (d.kind == DatumKind::kHole) {
      sigma = rms * std::sqrt(2.0 / n);
      dirs = d.direction.isZero() ? std::vector<Vec3>{d.normal.unitOrthogonal(),
                                                      d.normal.cross(d.normal.unitOrthogonal())}
                                  : std::vector<Vec3>{d.direction};
    } else if (d.kind == DatumKind::kSlot) {
      sigma = rms / std::sqrt(0.5 * n);
      dirs = {d.direction};
    } else if (d.kind == DatumKind::kEdge) {  // the skin's end: its points' spread across it
      dirs = {d.direction};
    }
    for (const Vec3& u : dirs) {
      Eigen::Matrix<double, 6, 1> row;
      row << (d.point - o).cross(u), u;
      info += row * row.transpose() / (sigma * sigma);
    }
  }
  const Eigen::Matrix<double, 6, 6> cov = info.inverse();
  double shift = 0.0;
  for (const Vec3& q : points) {
    Eigen::Matrix<double, 3, 6> A;
    const Vec3 r = q - o;
    A << 0, r.z(), -r.y(), 1, 0, 0, -r.z(), 0, r.x(), 0, 1, 0, r.y(), -r.x(), 0, 0, 0, 1;
    const Mat3 c = A * cov * A.transpose();
    shift =
        std::max(shift, std::sqrt(Eigen::SelfAdjointEigenSolver<Mat3>(c).eigenvalues().maxCoeff()));
  }
  const double rot = std::sqrt(
      Eigen::SelfAdjointEigenSolver<Mat3>(cov.topLeftCorner<3, 3>()).eigenvalues().maxCoeff());
  return {rot * 180.0 / std::numbers::pi, shift};
}

inline std::pair<double, double> datum_frame_error(const Transform& E,
                                                   const std::vector<Vec3>& points) {
  double shift = 0.0;
  for (const Vec3& p : points) shift = std::max(shift, (E * p - p).norm());
  return {Eigen::AngleAxisd(E.linear()).angle() * 180.0 / std::numbers::pi, shift};
}

}  // namespace springscan::analysis::testing
