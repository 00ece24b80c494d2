#include "tests/report/report_fixture.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>

#include "simulators/parts/sheet_profile.hpp"

namespace springscan::report::testing {
using namespace springscan::parts;  // test and demo parts (simulators/parts)
namespace {

using analysis::Vec3;
using parts::ProfileElement;

constexpr double kWidthMm = 80.0;

// Position and reference-side normal at arc length s along the path.
std::pair<Eigen::Vector2d, Eigen::Vector2d> at_length(const std::vector<ProfileElement>& path,
                                                      double s) {
  for (const auto& e : path) {
    const double len = e.length_mm();
    if (s > len && &e != &path.back()) {
      s -= len;
      continue;
    }
    const double t = std::clamp(s / len, 0.0, 1.0);
    Eigen::Vector2d d;
    Eigen::Vector2d p;
    if (e.kind == ProfileElement::Kind::kLine) {
      d = (e.end - e.start).normalized();
      p = e.start + t * (e.end - e.start);
    } else {
      const double angle = e.start_angle_rad + t * e.sweep_rad;
      p = e.center + e.radius_mm * Eigen::Vector2d(std::cos(angle), std::sin(angle));
      d = (e.sweep_rad > 0 ? 1.0 : -1.0) * Eigen::Vector2d(-std::sin(angle), std::cos(angle));
    }
    return {p, Eigen::Vector2d(-d.y(), d.x())};
  }
  return {Eigen::Vector2d::Zero(), Eigen::Vector2d::UnitY()};
}

v1::Vec3 vec(const Vec3& v) {
  v1::Vec3 out;
  out.set_x(v.x());
  out.set_y(v.y());
  out.set_z(v.z());
  return out;
}

void fill_report(const std::vector<ProfileElement>& path, double total_mm,
                 v1::InspectionReport& r) {
  r.set_schema("springscan.report.v1");
  r.set_software_version("0.1.0");
  r.set_created_utc("2026-11-22T00:30:00Z");
  r.set_station("press-line-3 <cell \"A\">");
  r.set_job_id(42);
  r.set_result_seq(7);
  r.mutable_input()->set_part_id("HAT-7 <rev&B>");
  r.mutable_input()->set_cad_file("parts/hat7.step");
  r.mutable_input()->set_scan_file("scans/hat7-0042.ply");
  auto* verdict = r.mutable_verdict();
  verdict->set_pass(false);
  verdict->add_reasons("bend B2 springback +2.40\u00b0 exceeds \u00b11.00\u00b0");
  verdict->add_reasons("p95 deviation 0.61 mm > tolerance 0.50 mm");
  for (double e : {417.95, 36.29, 9.81, 3.02, 1.35, 1.11, 1.07, 1.06, 1.06})
    r.mutable_global_fit()->add_error_history(e);
  r.mutable_global_fit()->set_method("point_to_plane");
  r.mutable_global_fit()->set_iterations(8);
  r.mutable_settings()->mutable_registration()->set_error_ratio_stop(0.995);
  const double springback[] = {0.4, 2.4, -0.3, 0.0};
  for (const auto& e : path) {
    if (e.kind != ProfileElement::Kind::kArc) continue;
    auto* b = r.add_bends();
    const int i = e.bend_index;
    b->set_id(i + 1);
    *b->mutable_axis_point() = vec(parts::profile_to_3d(e.center, 0.5 * kWidthMm));
    *b->mutable_axis_direction() = vec(Vec3::UnitY());
    b->set_radius_mm(e.radius_mm);
    b->set_nominal_angle_deg(std::abs(e.sweep_rad) * 180.0 / std::numbers::pi);
    b->set_measured(i != 3);  // B4: a flange too short to fit
    b->set_springback_deg(springback[i]);
    b->set_measured_angle_deg(b->nominal_angle_deg() - springback[i]);
    b->set_angle_tolerance_deg(1.0);
    b->set_pass(std::abs(springback[i]) <= 1.0);
    b->set_segment_a(i);
    b->set_segment_b(i + 1);
    if (i == 1) {  // B2: its angle along the bend, opening towards one end
      for (int k = 0; k < 3; ++k) {
        auto* station = b->add_angle_along_bend();
        station->set_position_mm(-20.0 + 20.0 * k);
        station->set_springback_deg(springback[i] + 0.3 * (k - 1));
        station->set_angle_deg(b->nominal_angle_deg() - station->springback_deg());
      }
      b->set_angle_min_deg(b->nominal_angle_deg() - springback[i] - 0.3);
      b->set_angle_max_deg(b->nominal_angle_deg() - springback[i] + 0.3);
      b->set_angle_spread_deg(0.6);
      b->set_measured_radius_mm(e.radius_mm + 0.07);
    }
    b->set_end_tangents(i == 2);  // B3: next to the curled wall S3
  }
  for (int s = 0; s < 5; ++s) {
    auto* seg = r.add_segments();
    seg->set_id(s);
    seg->add_cad_faces(2 * s);
    seg->set_points(1000 + 10 * s);
    seg->mutable_local_fit()->set_rms(0.05 + 0.01 * s);
    seg->set_shape_measured(s != 4);
    seg->set_flatness_mm(s == 3 ? 1.234 : 0.081);
    seg->set_flatness_rms_mm(0.02);
    if (s == 3) seg->set_curl_radius_mm(-240.0);
    seg->set_twist_deg_per_100mm(0.125);
    if (s == 0) {  // the first brim's free edge: 0.31 mm long, 0.52 mm low
      auto* edge = seg->mutable_edge_deviation_mm();
      edge->set_strips(3);
      edge->set_in_plane_mean(0.31);
      edge->set_in_plane_min(0.29);
      edge->set_in_plane_max(0.33);
      edge->set_across_mean(-0.52);
      edge->set_across_min(-0.55);
      edge->set_across_max(-0.49);
      // Where the edge is drawn: the path's start, 0.31 mm beyond it and 0.52 mm low.
      const auto [p, n] = at_length(path, 0.0);
      const Eigen::Vector2d out = -(at_length(path, 1.0).first - p).normalized();
      for (int k = 0; k < 3; ++k) {
        const double y = (k + 0.5) * kWidthMm / 3.0;
        *edge->add_cad_edge() = vec(parts::profile_to_3d(p, y));
        *edge->add_scan_edge() = vec(parts::profile_to_3d(p + 0.31 * out - 0.52 * n, y));
      }
      edge->set_kind("free");
      *seg->add_trim_edges() = *edge;
    }
    if (s == 2) {  // the web's side edge at y = 0: 0.12 mm drawn in, 0.04 mm high
      auto* edge = seg->add_trim_edges();
      edge->set_kind("side");
      edge->set_strips(3);
      edge->set_in_plane_mean(-0.12);
      edge->set_in_plane_min(-0.15);
      edge->set_in_plane_max(-0.1);
      edge->set_across_mean(0.04);
      edge->set_across_min(0.03);
      edge->set_across_max(0.05);
      const double start = 0.4 * total_mm, end = 0.6 * total_mm;
      for (int k = 0; k < 3; ++k) {
        const auto [p, n] = at_length(path, start + (k + 0.5) * (end - start) / 3.0);
        *edge->add_cad_edge() = vec(parts::profile_to_3d(p, 0.0));
        *edge->add_scan_edge() = vec(parts::profile_to_3d(p + 0.04 * n, 0.12));
      }
    }
  }
  // Compensation: opposite of the deviation field at 60 control points along the profile.
  for (int k = 0; k < 60; ++k) {
    const double s = (k + 0.5) / 60.0 * total_mm;
    const auto [p, n] = at_length(path, s);
    const double dev = 0.6 * std::sin(2 * std::numbers::pi * s / total_mm);
    auto* c = r.add_compensation();
    *c->mutable_point() = vec(parts::profile_to_3d(p, 0.5 * kWidthMm));
    *c->mutable_vector() = vec(-dev * parts::profile_to_3d(n, 0.0));
  }
  r.mutable_timings_ms()->set_total(812.0);
  r.mutable_timings_ms()->set_global_fit(301.5);
  r.add_warnings("flange S4 has 12 points: bend B4 not measured");
}

}  // namespace

Fixture make_fixture(std::size_t points) {
  Fixture f;
  const auto path = parts::profile_path(parts::hat_profile(30, 40, 50, 90, 4));
  double total = 0.0;
  for (const auto& e : path) total += e.length_mm();
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> along(0.0, total), across(0.0, kWidthMm);
  std::normal_distribution<double> noise(0.0, 0.02);
  f.cloud.points.reserve(points);
  f.cloud.scalars.reserve(points);
  double lo = 1e9, hi = -1e9, sum = 0.0, sum_sq = 0.0;
  std::size_t out = 0;
  for (std::size_t k = 0; k < points; ++k) {
    const double s = along(rng), y = across(rng);
    const auto [p, n] = at_length(path, s);
    const double dev = 0.6 * std::sin(2 * std::numbers::pi * s / total) + noise(rng);
    f.cloud.points.push_back(parts::profile_to_3d(p + dev * n, y));
    f.cloud.scalars.push_back(dev);
    lo = std::min(lo, dev);
    hi = std::max(hi, dev);
    sum += dev;
    sum_sq += dev * dev;
    out += std::abs(dev) > 0.5 ? 1 : 0;
  }
  fill_report(path, total, f.report);
  auto* d = f.report.mutable_deviation();
  d->set_min(lo);
  d->set_max(hi);
  const double n = static_cast<double>(std::max<std::size_t>(points, 1));
  d->set_mean(sum / n);
  d->set_rms(std::sqrt(sum_sq / n));
  d->set_p95(0.61);
  d->set_fraction_out_of_tolerance(static_cast<double>(out) / n);
  d->set_reference("cad_surface");
  d->set_tolerance_mm(0.5);
  d->set_points(static_cast<std::int64_t>(points));
  return f;
}

}  // namespace springscan::report::testing
