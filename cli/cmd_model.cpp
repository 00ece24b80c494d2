// springscan model: load a CAD file and show what the station will see of it: faces, flanges
// and bends, as text or JSON, so a user can check a part before it goes on the line.
#include <cstdio>
#include <iostream>
#include <sstream>
#include <string>

#include "analysis/cad/datum_features.hpp"
#include "analysis/cad/import.hpp"
#include "analysis/cad/segmentation.hpp"
#include "cli/cli_common.hpp"

namespace springscan::cli {
namespace {

constexpr const char* kName = "model";

std::string vec(const analysis::Vec3& v) {
  char text[96];
  std::snprintf(text, sizeof text, "[%.9g, %.9g, %.9g]", v.x(), v.y(), v.z());
  return text;
}

std::string ids(const std::vector<int>& list) {
  std::string out = "[";
  for (std::size_t i = 0; i < list.size(); ++i) out += (i ? ", " : "") + std::to_string(list[i]);
  return out + "]";
}

std::string quoted(const std::string& text) {
  std::string out = "\"";
  for (char c : text) {
    if (c == '"' || c == '\\') out += '\\';
    if (static_cast<unsigned char>(c) >= 0x20) out += c;
  }
  return out + "\"";
}

// The datum candidates (docs/alignment.md "Datum alignment"): what a datum list is written from.
std::string candidates_json(const analysis::DatumCandidates& c) {
  std::ostringstream o;
  o.precision(10);
  o << "{\n    \"pads\": [";
  for (std::size_t i = 0; i < c.pads.size(); ++i) {
    const auto& p = c.pads[i];
    o << (i ? "," : "") << "\n      {\"flange\": " << p.flange_id << ", \"point\": " << vec(p.point)
      << ", \"normal\": " << vec(p.normal) << ", \"area_mm2\": " << p.area_mm2
      << ", \"thickness_mm\": " << p.thickness_mm << "}";
  }
  o << "\n    ],\n    \"holes\": [";
  for (std::size_t i = 0; i < c.holes.size(); ++i) {
    const auto& h = c.holes[i];
    o << (i ? "," : "") << "\n      {\"faces\": " << ids(h.face_ids)
      << ", \"flange\": " << h.flange_id << ", \"centre\": " << vec(h.centre)
      << ", \"axis\": " << vec(h.axis) << ", \"diameter_mm\": " << h.diameter_mm
      << ", \"thickness_mm\": " << h.thickness_mm << "}";
  }
  o << "\n    ],\n    \"slots\": [";
  for (std::size_t i = 0; i < c.slots.size(); ++i) {
    const auto& sl = c.slots[i];
    o << (i ? "," : "") << "\n      {\"faces\": " << ids(sl.face_ids)
      << ", \"flange\": " << sl.flange_id << ", \"centre\": " << vec(sl.centre)
      << ", \"axis\": " << vec(sl.axis) << ", \"direction\": " << vec(sl.direction)
      << ", \"width_mm\": " << sl.width_mm << ", \"length_mm\": " << sl.length_mm
      << ", \"thickness_mm\": " << sl.thickness_mm << "}";
  }
  o << "\n    ]\n  }";
  return o.str();
}

std::string as_json(const analysis::CadLoadReport& r,
                    const std::vector<analysis::CadFaceInfo>& faces,
                    const analysis::PartSegmentation& s, const analysis::DatumCandidates& c) {
  std::ostringstream o;
  o.precision(10);
  const auto size = r.bbox_max - r.bbox_min;
  o << "{\n  \"file\": " << quoted(r.file) << ",\n  \"format\": " << quoted(r.format)
    << ",\n  \"faces\": " << r.faces << ",\n  \"shells\": " << r.shells
    << ",\n  \"solids\": " << r.solids << ",\n  \"free_edges\": " << r.free_edges
    << ",\n  \"area_mm2\": " << r.area_mm2 << ",\n  \"bbox_size_mm\": " << vec(size)
    << ",\n  \"scale_applied\": " << r.scale_applied << ",\n  \"face_list\": [";
  for (std::size_t i = 0; i < faces.size(); ++i) {
    const auto& f = faces[i];
    o << (i ? "," : "") << "\n    {\"id\": " << f.id << ", \"type\": " << quoted(f.type)
      << ", \"area_mm2\": " << f.area_mm2 << ", \"neighbors\": " << ids(f.neighbors);
    if (f.type == "plane") o << ", \"normal\": " << vec(f.direction);
    if (f.type == "cylinder")
      o << ", \"axis_point\": " << vec(f.axis_point) << ", \"axis_direction\": " << vec(f.direction)
        << ", \"radius_mm\": " << f.radius_mm;
    o << "}";
  }
  o << "\n  ],\n  \"flanges\": [";
  for (std::size_t i = 0; i < s.flanges.size(); ++i) {
    const auto& f = s.flanges[i];
    o << (i ? "," : "") << "\n    {\"id\": " << f.id << ", \"faces\": " << ids(f.face_ids)
      << ", \"point\": " << vec(f.point) << ", \"normal\": " << vec(f.normal)
      << ", \"area_mm2\": " << f.area_mm2 << "}";
  }
  o << "\n  ],\n  \"bends\": [";
  for (std::size_t i = 0; i < s.bends.size(); ++i) {
    const auto& b = s.bends[i];
    o << (i ? "," : "") << "\n    {\"id\": " << b.id << ", \"faces\": " << ids(b.face_ids)
      << ", \"axis_point\": " << vec(b.axis_point)
      << ", \"axis_direction\": " << vec(b.axis_direction) << ", \"radius_mm\": " << b.radius_mm
      << ", \"nominal_angle_deg\": " << b.nominal_angle_deg << ", \"flange_a\": " << b.flange_a
      << ", \"flange_b\": " << b.flange_b << "}";
  }
  o << "\n  ],\n  \"other_faces\": " << ids(s.other_faces)
    << ",\n  \"datum_candidates\": " << candidates_json(c) << "\n}\n";
  return o.str();
}

std::string as_text(const analysis::CadLoadReport& r,
                    const std::vector<analysis::CadFaceInfo>& faces,
                    const analysis::PartSegmentation& s, const analysis::DatumCandidates& c) {
  std::ostringstream o;
  o.precision(6);
  o << r.file << "\n  " << analysis::summary(r) << "\n\nfaces (" << faces.size() << "):\n";
  for (const auto& f : faces) {
    o << "  " << f.id << "  " << f.type << "  area " << f.area_mm2 << " mm2";
    if (f.type == "cylinder") o << "  radius " << f.radius_mm << " mm";
    o << "  neighbours " << ids(f.neighbors) << "\n";
  }
  o << "\nflanges (" << s.flanges.size() << "):\n";
  for (const auto& f : s.flanges)
    o << "  " << f.id << "  faces " << ids(f.face_ids) << "  normal " << vec(f.normal) << "  area "
      << f.area_mm2 << " mm2\n";
  o << "\nbends (" << s.bends.size() << "):\n";
  for (const auto& b : s.bends)
    o << "  " << b.id << "  flanges " << b.flange_a << "-" << b.flange_b << "  angle "
      << b.nominal_angle_deg << " deg  inner radius " << b.radius_mm << " mm  axis "
      << vec(b.axis_point) << " + t " << vec(b.axis_direction) << "  faces " << ids(b.face_ids)
      << "\n";
  o << "\nother faces: " << ids(s.other_faces) << "\n";
  o << "\ndatum candidates: pads (" << c.pads.size() << ")\n";
  for (const auto& p : c.pads)
    o << "  flange " << p.flange_id << "  area " << p.area_mm2 << " mm2  point " << vec(p.point)
      << "  normal " << vec(p.normal) << "\n";
  o << "datum candidates: round holes (" << c.holes.size() << ")\n";
  for (const auto& h : c.holes)
    o << "  diameter " << h.diameter_mm << " mm  centre " << vec(h.centre) << "  axis "
      << vec(h.axis) << "  flange " << h.flange_id << "  faces " << ids(h.face_ids) << "\n";
  o << "datum candidates: slots (" << c.slots.size() << ")\n";
  for (const auto& sl : c.slots)
    o << "  width " << sl.width_mm << " mm  length " << sl.length_mm << " mm  centre "
      << vec(sl.centre) << "  across " << vec(sl.direction) << "  flange " << sl.flange_id
      << "  faces " << ids(sl.face_ids) << "\n";
  return o.str();
}

}  // namespace

int model_main(int argc, char** argv) {
  ArgParser args(
      kName, "springscan model PART.igs|PART.step|PART.brep [--json]",
      "Loads a CAD file as the station would (mm, sewn, healed) and prints its faces, "
      "flanges and bends (axis, inner radius, nominal angle, the flanges joined), and the "
      "candidate datum features (planar pads by area, round holes, slots).");
  args.add_switch("json", "print JSON instead of text");
  args.add_option("linear-deflection", "MM", "tessellation chord tolerance (default 0.05)");
  Logger log;
  if (auto exit_code = args.start(argc, argv, log)) return *exit_code;
  if (args.positionals().size() != 1) return fail_with(kName, "expected one CAD file", kExitUsage);
  analysis::CadImportSettings settings;
  if (args.has("linear-deflection")) {
    const auto mm = args.get_number("linear-deflection");
    if (!mm || !(*mm > 0.0))
      return fail_with(kName,
                       "--linear-deflection " + args.get("linear-deflection") +
                           ": expected a positive number of mm",
                       kExitUsage);
    settings.linear_deflection_mm = *mm;
  }
  const auto shape = analysis::load_cad(args.positionals()[0], settings);
  if (!shape) return fail_with(kName, shape.message(), kExitUsage);
  const auto faces = analysis::describe_faces(*shape);
  const auto segmentation = analysis::segment_cad(*shape);
  const auto candidates = analysis::datum_candidates(*shape, faces, segmentation);
  std::cout << (args.has("json") ? as_json(shape->report(), faces, segmentation, candidates)
                                 : as_text(shape->report(), faces, segmentation, candidates));
  return kExitOk;
}

}  // namespace springscan::cli
