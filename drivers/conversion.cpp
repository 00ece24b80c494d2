#include "drivers/conversion.hpp"

#include <cmath>

#include "drivers/wire.hpp"

namespace springscan::drivers {

std::string validate(const LaserCalibration& c) {
  const auto unit = [](const analysis::Vec3& v) { return std::abs(v.norm() - 1.0) < 1e-6; };
  if (!unit(c.x_axis)) return "laser calibration: x_axis is not a unit vector";
  if (!unit(c.z_axis)) return "laser calibration: z_axis is not a unit vector";
  if (std::abs(c.x_axis.dot(c.z_axis)) > 1e-6)
    return "laser calibration: x_axis and z_axis are not orthogonal";
  if (!c.origin_mm.allFinite() || !c.motion_axis.allFinite() || c.motion_axis.norm() == 0.0)
    return "laser calibration: origin or motion_axis not finite, or motion_axis zero";
  return "";
}

std::size_t append_laser_profile(const LaserProfileView& profile, const LaserCalibration& c,
                                 std::vector<analysis::Vec3>& out) {
  // §4.1: p = origin + x * x_axis + z * z_axis + encoder * motion_axis; the encoder term is
  // the same for the whole profile.
  const analysis::Vec3 base = c.origin_mm + profile.encoder_mm * c.motion_axis;
  const std::size_t start = out.size();
  out.resize(start + profile.count);
  analysis::Vec3* dst = out.data() + start;
  const std::uint8_t* src = profile.points.data();
  std::size_t kept = 0;
  for (std::size_t i = 0; i < profile.count; ++i, src += protocol::kProfilePointBytes) {
    const float x = wire::load_f32(src);
    const float z = wire::load_f32(src + 4);
    dst[kept] = base + double(x) * c.x_axis + double(z) * c.z_axis;
    kept += std::isnan(z) ? 0 : 1;  // branch-free: a NaN point is overwritten by the next
  }
  out.resize(start + kept);
  return kept;
}

std::size_t append_probe_batch(const ProbeBatchView& batch, const ProbeCalibration& c,
                               std::vector<analysis::Vec3>& out,
                               std::vector<analysis::Vec3>* normals) {
  const analysis::Mat3 R = c.T_part_machine.linear();
  for (std::size_t i = 0; i < batch.count; ++i) {
    const ProbeRecord r = probe_record(batch, i);
    const analysis::Vec3 centre(r.center_mm[0], r.center_mm[1], r.center_mm[2]);
    const analysis::Vec3 dir =
        analysis::Vec3(r.direction[0], r.direction[1], r.direction[2]).normalized();
    // §4.2 stylus radius compensation: the stylus touched the surface one radius further along
    // the direction it was moving.
    out.push_back(c.T_part_machine * (centre + double(r.stylus_radius_mm) * dir));
    if (normals != nullptr) normals->push_back(-(R * dir));
  }
  return batch.count;
}

}  // namespace springscan::drivers
