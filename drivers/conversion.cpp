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
  const analysis::Vec3 t = c.T_part_machine.translation();
  const std::size_t start = out.size();
  out.resize(start + batch.count);
  if (normals != nullptr) normals->resize(start + batch.count);
  const std::uint8_t* q = batch.records.data();
  for (std::size_t i = 0; i < batch.count; ++i, q += protocol::kProbeRecordBytes) {
    // §4.2 record layout: centre 3 x f64, direction 3 x f32, radius f32.
    const analysis::Vec3 centre(wire::load_f64(q), wire::load_f64(q + 8), wire::load_f64(q + 16));
    analysis::Vec3 dir(wire::load_f32(q + 24), wire::load_f32(q + 28), wire::load_f32(q + 32));
    dir /= dir.norm();  // unit on the wire up to float rounding
    // §4.2 stylus radius compensation: the stylus touched the surface one radius further along
    // the direction it was moving.
    out[start + i] = R * (centre + double(wire::load_f32(q + 36)) * dir) + t;
    if (normals != nullptr) (*normals)[start + i] = -(R * dir);
  }
  return batch.count;
}

}  // namespace springscan::drivers
