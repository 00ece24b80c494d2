#pragma once
// The CAD side in one call: load, sample, segment and index a part for exact distances,
// with an on-disk model cache keyed by the CAD file's SHA-256 so that a restart is fast.

#include <string>

#include "analysis/cad/distance.hpp"
#include "analysis/cad/import.hpp"
#include "analysis/cad/sampling.hpp"
#include "analysis/cad/segmentation.hpp"
#include "analysis/core/expected.hpp"
#include "analysis/core/part_model.hpp"

namespace springscan::analysis {

struct CadModelSettings {
  CadImportSettings import;              ///< units, sewing, healing, tessellation
  CadSamplingSettings sampling;          ///< number of even samples, seed
  CadSegmentationSettings segmentation;  ///< flange and bend rules
  CadDistanceSettings distance;          ///< exact distance queries
};

/// Loads IGES/STEP/BRep at `path` and builds the PartModel: samples (points, exact normals, face
/// ids), segmentation, face_count and an exact SurfaceDistance (which keeps the shape alive).
/// Errors name the file and the step that failed.
Expected<PartModel> load_part_model(const std::string& path, const CadModelSettings& settings = {});

/// A model from the cache or freshly built, and how it was obtained.
struct CachedModelLoad {
  PartModel model;
  bool cache_hit = false;  ///< true: read from cache_file, no IGES/STEP parsing or healing
  std::string cache_file;  ///< where the model is (or would have been) cached
  std::string source_sha256;
  std::string cache_error;  ///< non-empty when the cache could not be written (the model is fine)
};

/// load_part_model through a cache in `cache_dir` (created if missing): the cache file is named
/// by the SHA-256 of the CAD file's bytes and also records the settings, so a changed file or
/// changed settings miss and rebuild (the entry is then rewritten, atomically). A missing,
/// unreadable or corrupt entry is a miss, never an error. Not safe against two processes
/// writing the same entry at once beyond the atomic rename (last writer wins).
Expected<CachedModelLoad> load_part_model_cached(const std::string& path,
                                                 const std::string& cache_dir,
                                                 const CadModelSettings& settings = {});

/// The shape's tessellation as PartModel::mesh holds it (vertices and triangles, CAD frame).
TriangleMesh tessellation(const CadShape& shape);

/// The settings that shape a cached model, as one canonical string (part of the cache key).
std::string cache_settings_key(const CadModelSettings& settings);

}  // namespace springscan::analysis
