#pragma once
// PRIVATE to analysis/cad_*.cpp: the OpenCASCADE side of CadShape. This is the one header that
// includes OpenCASCADE; it is never included by a public header or outside analysis/cad_*.cpp
// (STYLE.md section 1: foreign types stay in adapter files at the folder's edge).

#include <TopTools_IndexedMapOfShape.hxx>
#include <TopoDS.hxx>
#include <TopoDS_Face.hxx>
#include <TopoDS_Shape.hxx>
#include <mutex>
#include <string>

#include "analysis/cad_import.hpp"

namespace springscan::analysis {

/// Immutable after construction: every query reads it concurrently.
struct CadShape::Impl {
  TopoDS_Shape shape;
  TopTools_IndexedMapOfShape faces;  ///< face id i (0-based) = faces(i + 1)
  CadLoadReport report;
  CadMesh mesh;

  const TopoDS_Face& face(int id) const { return TopoDS::Face(faces(id + 1)); }
};

/// OpenCASCADE's data exchange keeps its parameters (units, modes) in process-wide statics
/// (Interface_Static), so every reader and writer call holds this lock.
std::mutex& occt_exchange_mutex();

/// Heals nothing and reads nothing: counts, measures and tessellates `shape` into a CadShape.
/// `report` carries what the caller already knows (file, format, sewing, scale).
Expected<CadShape> make_cad_shape(const TopoDS_Shape& shape, CadLoadReport report,
                                  const CadImportSettings& settings);

/// "what: message" for an OpenCASCADE exception.
std::string describe_occt_failure(const std::string& what, const char* message);

}  // namespace springscan::analysis
