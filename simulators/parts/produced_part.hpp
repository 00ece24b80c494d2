#pragma once
// Any segmented CAD part as it comes off the press: each bend opened by a chosen springback, the
// rest of the part carried along rigidly (docs/springback.md, "Parts as produced").
//
// The flanges and bends form a graph (a bend joins two flanges). From a root flange (the largest
// unless chosen), a breadth-first walk gives every other flange a parent bend; everything beyond
// bend i turns rigidly by its springback about the bend axis so that the bend opens (the angle
// the sheet turns becomes nominal - springback). Inside a bend zone a point at angular position
// phi of the span Phi turns by springback * phi / Phi about the axis: the zone stays a cylinder
// of the same radius and stays tangent to both flanges. Faces that are neither flange nor bend
// (sheet edges, cut faces, holes, reliefs) move point by point with the region they touch: the
// nearest flange or bend through the face adjacency, and the bend rule wherever the point lies in
// a bend's wedge. Closed hems (nominal >= hem_angle_deg) keep springback 0.
//
// The produced part keeps the CAD frame of the root flange: the root does not move.

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "analysis/cad/import.hpp"
#include "analysis/cad/model.hpp"
#include "analysis/cad/segmentation.hpp"
#include "analysis/core/expected.hpp"
#include "analysis/core/part_model.hpp"

namespace springscan::parts {

// The parts are built of the analysis types (points, models, segmentation).
using namespace springscan::analysis;

struct ProducedPartSettings {
  int root_flange = -1;          ///< Flange::id that stays in place; -1: the largest by area
  double hem_angle_deg = 175.0;  ///< bends at least this sharp are closed hems: springback 0
  /// A point of a non-flange, non-bend face counts as inside a bend's wedge when its distance
  /// from the bend axis lies within [inner radius, inner radius + thickness] widened by this.
  double wedge_tolerance_mm = 0.05;
};

/// The ground truth of one bend of the produced part.
struct BendTruth {
  int bend_id = 0;                        ///< Bend::id
  int parent_flange = -1;                 ///< the flange on the root side (does not turn here)
  int child_flange = -1;                  ///< the flange that turns by springback_deg
  Vec3 axis_point = Vec3::Zero();         ///< on the produced bend axis (produced frame, mm)
  Vec3 axis_direction = Vec3::UnitX();    ///< unit; the child turns by +produced angle about it
  double radius_mm = 0.0;                 ///< inner radius (unchanged by springback)
  double nominal_angle_deg = 0.0;         ///< the angle the sheet turns in the CAD part
  double requested_springback_deg = 0.0;  ///< as asked
  double springback_deg = 0.0;      ///< applied: as asked, or 0 for a closed hem; positive = opened
  double produced_angle_deg = 0.0;  ///< nominal - springback for a tree bend
  bool hem = false;                 ///< closed hem: springback forced to 0
  /// The bend closes a cycle of the flange graph: its two flanges were placed through other
  /// bends, so its springback could not be applied; produced_angle_deg is what it came out as.
  bool closes_cycle = false;
  double cycle_error_deg = 0.0;  ///< closing bends: produced - (nominal - requested springback)
};

/// How the walk went, for logs and tests.
struct ProducedPartReport {
  int root_flange = -1;
  std::vector<int> hems;              ///< Bend::id of bends forced to springback 0
  std::vector<int> closing_bends;     ///< Bend::id of bends that close a cycle
  std::vector<int> rigid_flanges;     ///< flanges reached through no bend: moved with a face
                                      ///< neighbour's flange (or not at all), listed here
  std::vector<std::string> warnings;  ///< one line per oddity (hem forced, cycle, unattached)
};

struct ProducedPartData;  // the lookup structures behind produced() (produced_part.cpp)

/// A CAD part as produced. Copies share the immutable lookup data; every const member may be
/// called from many threads.
struct ProducedPart {
  std::vector<Transform> flange_transforms;  ///< per Flange::id: T_produced_cad of the flange
  std::vector<BendTruth> bends;              ///< per Bend::id
  PointCloud samples;  ///< the model's samples, produced (points, normals, face ids)
  CadMesh mesh;        ///< the tessellation produced: vertices moved, triangles and uv as CAD
  CadMesh cad_mesh;    ///< the CAD tessellation (a scan snaps its hits to the CAD surface)
  std::vector<CadFaceInfo> faces;  ///< the CAD faces (describe_faces): type, plane, cylinder
  bool solid = false;              ///< the shape is a solid: its back faces are never seen
  ProducedPartReport report;
  std::shared_ptr<const ProducedPartData> data;

  /// Where the CAD point `cad_point` of face `face_id` lies on the produced part.
  Vec3 produced(const Vec3& cad_point, int face_id) const {
    return local_transform(cad_point, face_id) * cad_point;
  }
  /// The rigid motion of the material at that point (rotate CAD normals by its linear part).
  Transform local_transform(const Vec3& cad_point, int face_id) const;
};

/// A CAD part as make_produced_part needs it: the shape and its PartModel.
struct CadPart {
  CadShape shape;
  PartModel model;  ///< samples, segmentation and face count (no exact distance)
};

/// Loads `path` once and builds the model from that shape with the same settings as
/// load_part_model (samples, segmentation), without its exact-distance index.
Expected<CadPart> load_cad_part(const std::string& path, const CadModelSettings& settings = {});

/// The part `model` (segmented; samples with face ids) of `shape` (its tessellation and face
/// adjacency) with springback_deg[i] at bend i (Bend::id). Errors: the shape's face count differs
/// from the model's, wrong number of springback values, an empty segmentation, a bad root flange.
Expected<ProducedPart> make_produced_part(const PartModel& model, const CadShape& shape,
                                          const std::vector<double>& springback_deg,
                                          const ProducedPartSettings& settings = {});

}  // namespace springscan::parts
