// settings.alignment <-> DatumAlignmentSettings and report.alignment.
#include "analysis/messages/alignment_proto.hpp"

#include <gtest/gtest.h>

namespace springscan::analysis {
namespace {

void put(double x, double y, double z, v1::Vec3* v) {
  v->set_x(x);
  v->set_y(y);
  v->set_z(z);
}

v1::AlignmentSettings three_two_one() {
  v1::AlignmentSettings m;
  const double pads[3][2] = {{10, 10}, {90, 10}, {50, 52}};
  for (int k = 0; k < 3; ++k) {
    v1::Datum& d = *m.add_datums();
    d.set_name(std::string(1, 'A') += std::to_string(k + 1));
    d.set_kind(v1::Datum::PAD);
    put(pads[k][0], pads[k][1], 0, d.mutable_point());
    put(0, 0, 2, d.mutable_normal());  // normalised on reading
  }
  for (int k = 0; k < 2; ++k) {
    v1::Datum& d = *m.add_datums();
    d.set_name(k ? "C" : "B");
    d.set_kind(v1::Datum::HOLE);
    put(k ? 80 : 20, 30, 0, d.mutable_point());
    put(0, 0, 1, d.mutable_normal());
    d.set_diameter_mm(8);
    if (k) put(0, 1, 1e-4, d.mutable_direction());  // written to a few digits: projected
  }
  return m;
}

TEST(AlignmentProto, ReadsADatumList) {
  auto s = from_proto(three_two_one());
  ASSERT_TRUE(s) << s.message();
  ASSERT_EQ(s->datums.size(), 5u);
  EXPECT_EQ(s->datums[0].kind, DatumKind::kPad);
  EXPECT_DOUBLE_EQ(s->datums[0].normal.z(), 1.0);
  EXPECT_EQ(s->datums[4].direction, Vec3::UnitY());
  EXPECT_TRUE(s->datums[3].direction.isZero());
  EXPECT_EQ(s->datums[3].weight, 1.0);
  // And back: the settings in force read the same.
  v1::AlignmentSettings out;
  to_proto(*s, &out);
  auto again = from_proto(out);
  ASSERT_TRUE(again) << again.message();
  EXPECT_EQ(again->datums[4].direction, s->datums[4].direction);
  EXPECT_EQ(out.datums(3).diameter_mm(), 8.0);
  EXPECT_EQ(out.search_mm(), s->search_mm);
}

TEST(AlignmentProto, RefusesWhatCannotBeSolved) {
  auto m = three_two_one();
  m.mutable_datums(4)->clear_kind();
  auto s = from_proto(m);
  ASSERT_FALSE(s);
  EXPECT_EQ(s.code(), ErrorCode::kInvalidSettings);
  EXPECT_NE(s.message().find("'C'"), std::string::npos) << s.message();
  m = three_two_one();
  m.mutable_datums()->RemoveLast();
  s = from_proto(m);
  ASSERT_FALSE(s);
  EXPECT_NE(s.message().find("free"), std::string::npos) << s.message();
  EXPECT_TRUE(from_proto(v1::AlignmentSettings{}));  // no datums: the best fit
}

TEST(AlignmentProto, BestFitWithoutDatums) {
  Transform T = Transform::Identity();
  T.translation() = Vec3(1, 2, 3);
  v1::Alignment out;
  alignment_to_proto(T, nullptr, &out);
  EXPECT_EQ(out.method(), "best_fit");
  ASSERT_EQ(out.transform_size(), 16);
  EXPECT_EQ(out.transform(3), 1.0);
  EXPECT_EQ(out.datums_size(), 0);
}

}  // namespace
}  // namespace springscan::analysis
