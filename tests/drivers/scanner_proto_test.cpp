#include "drivers/scanner_proto.hpp"

#include <gtest/gtest.h>

namespace springscan::drivers {
namespace {

TEST(ScannerProto, DefaultsComeFromTheCppStructs) {
  v1::ScannerConfig c;
  c.set_kind(v1::ScannerConfig::LASER_LINE);
  const auto laser = laser_settings_from_proto(c);
  ASSERT_TRUE(laser.ok()) << laser.message();
  EXPECT_EQ(laser->link.usb.vendor_id, protocol::kVendorId);
  EXPECT_EQ(laser->link.usb.product_id, protocol::kProductIdLaser);
  EXPECT_EQ(laser->link.data_timeout_ms, LinkSettings{}.data_timeout_ms);
  EXPECT_TRUE(laser->calibration.z_axis.isApprox(LaserCalibration{}.z_axis));
  EXPECT_EQ(tactile_settings_from_proto(c)->link.usb.product_id, protocol::kProductIdTactile);
}

TEST(ScannerProto, SetFieldsOverrideAndAreValidated) {
  v1::ScannerConfig c;
  c.set_vendor_id(0x1234);
  c.set_serial("A7");
  c.set_timeout_s(0.25);
  c.mutable_laser_calibration()->mutable_motion_axis()->set_x(2.0);  // y, z stay 0
  const auto s = laser_settings_from_proto(c);
  ASSERT_TRUE(s.ok()) << s.message();
  EXPECT_EQ(s->link.usb.vendor_id, 0x1234);
  EXPECT_EQ(s->link.usb.serial, "A7");
  EXPECT_EQ(s->link.data_timeout_ms, 250);
  EXPECT_DOUBLE_EQ(s->calibration.motion_axis.x(), 2.0);

  c.set_vendor_id(0x10000);
  EXPECT_NE(laser_settings_from_proto(c).message().find("scanner.vendor_id = 65536"),
            std::string::npos);
  c.set_vendor_id(0x1209);
  c.mutable_laser_calibration()->mutable_x_axis()->set_x(1.0);  // a set Vec3 replaces the
  c.mutable_laser_calibration()->mutable_x_axis()->set_z(1.0);  // whole axis: (1, 0, 1)
  EXPECT_NE(laser_settings_from_proto(c).message().find("x_axis is not a unit vector"),
            std::string::npos);
  c.set_timeout_s(-1);
  EXPECT_NE(laser_settings_from_proto(c).message().find("scanner.timeout_s"), std::string::npos);
}

TEST(ScannerProto, TactileTransformMustBeRigidWithSixteenNumbers) {
  v1::ScannerConfig c;
  for (int i = 0; i < 15; ++i) c.add_t_part_machine(0.0);
  EXPECT_NE(tactile_settings_from_proto(c).message().find("15 numbers"), std::string::npos);
  c.clear_t_part_machine();
  // A quarter turn about z and a shift of (10, 20, 30).
  for (double v : {0., -1., 0., 10., 1., 0., 0., 20., 0., 0., 1., 30., 0., 0., 0., 1.})
    c.add_t_part_machine(v);
  const auto s = tactile_settings_from_proto(c);
  ASSERT_TRUE(s.ok()) << s.message();
  const analysis::Vec3 p = s->calibration.T_part_machine * analysis::Vec3(1, 0, 0);
  EXPECT_TRUE(p.isApprox(analysis::Vec3(10, 21, 30)));
  c.set_t_part_machine(0, 2.0);  // a scale is not rigid
  EXPECT_FALSE(tactile_settings_from_proto(c).ok());
}

TEST(ScannerProto, MakeScannerDefaultsToTheLaserAndRefusesAnUnknownKind) {
  v1::ScannerConfig c;  // no kind: the laser line scanner, like springscand always did
  EXPECT_TRUE(make_scanner(c).ok());
  EXPECT_TRUE(check_scanner_config(c).ok());
  c.set_kind(v1::ScannerConfig::TACTILE_PROBE);
  EXPECT_TRUE(make_scanner(c).ok());
  c.set_kind(static_cast<v1::ScannerConfig::Kind>(7));
  EXPECT_NE(make_scanner(c).message().find("scanner.kind = 7"), std::string::npos);
  EXPECT_FALSE(check_scanner_config(c).ok());
  c.set_kind(v1::ScannerConfig::LASER_LINE);
  c.mutable_laser_calibration()->mutable_x_axis()->set_x(2.0);  // not a unit vector
  EXPECT_FALSE(check_scanner_config(c).ok());
}

}  // namespace
}  // namespace springscan::drivers
