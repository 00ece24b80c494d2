#include "analysis/messages/uncertainty_proto.hpp"

namespace springscan::analysis {

Expected<UncertaintySettings> from_proto(const v1::UncertaintySettings& m) {
  UncertaintySettings s;
  if (m.has_scanner_sigma_mm()) s.scanner_sigma_mm = m.scanner_sigma_mm();
  if (m.has_calibration_angle_deg()) s.calibration_angle_deg = m.calibration_angle_deg();
  if (m.has_calibration_length_mm()) s.calibration_length_mm = m.calibration_length_mm();
  if (m.has_temperature_delta_k()) s.temperature_delta_k = m.temperature_delta_k();
  if (auto error = validate(s)) return *error;
  return s;
}

void to_proto(const UncertaintySettings& s, v1::UncertaintySettings* m) {
  m->set_scanner_sigma_mm(s.scanner_sigma_mm);
  m->set_calibration_angle_deg(s.calibration_angle_deg);
  m->set_calibration_length_mm(s.calibration_length_mm);
  m->set_temperature_delta_k(s.temperature_delta_k);
}

}  // namespace springscan::analysis
