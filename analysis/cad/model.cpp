// load_part_model and its cache (cad_model.hpp): load, sample, segment, index; the cached model
// is a v1::CachedPartModel (cad_model_proto.cpp) named by the CAD file's SHA-256.
#include "analysis/cad/model.hpp"

#include <Standard_Failure.hxx>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "analysis/cad/internal.hpp"
#include "analysis/io/file_io.hpp"
#include "analysis/io/sha256.hpp"
#include "analysis/messages/cad_model_proto.hpp"

namespace springscan::analysis {
namespace {

Expected<PartModel> build_model(const CadShape& shape, const CadModelSettings& settings) {
  auto samples = sample_cad(shape, settings.sampling);
  if (!samples) return samples.error();
  PartModel model;
  model.samples = std::move(*samples);
  try {
    model.segmentation = segment_cad(shape, settings.segmentation);
  } catch (const Standard_Failure& e) {
    return fail(
        describe_occt_failure(shape.report().file + ": segmentation", e.GetMessageString()));
  }
  model.face_count = shape.face_count();
  model.distance = make_cad_distance(shape, settings.distance);
  model.mesh = tessellation(shape);
  return model;
}

// A cache entry is used only when it parses and matches the file's hash and the settings.
Expected<PartModel> read_cache(const std::string& cache_file, const std::string& sha256,
                               const std::string& settings_key, const CadModelSettings& settings) {
  std::ifstream in(cache_file, std::ios::binary);
  if (!in) return fail(cache_file + ": no cache entry");
  v1::CachedPartModel message;
  if (!message.ParseFromIstream(&in)) return fail(cache_file + ": corrupt cache entry");
  if (message.format_version() != kCachedPartModelVersion || message.source_sha256() != sha256 ||
      message.settings_key() != settings_key)
    return fail(cache_file + ": stale cache entry");
  auto shape = cad_from_brep_text(message.brep(), cache_file, settings.import);
  if (!shape) return shape.error();
  auto model = from_proto(message);
  if (!model) return model.error();
  if (model->face_count != shape->face_count()) return fail(cache_file + ": face count mismatch");
  model->distance = make_cad_distance(*shape, settings.distance);
  model->mesh = tessellation(*shape);
  return model;
}

// Through the one atomic writer (fsync, rename, fsync of the folder), so neither a reader nor
// a power loss ever leaves half an entry.
std::string write_cache(const std::string& cache_file, const v1::CachedPartModel& message) {
  std::string bytes;
  if (!message.SerializeToString(&bytes)) return cache_file + ": cannot serialize the cache entry";
  const auto written = write_file_atomically(cache_file, bytes);
  return written ? std::string() : written.message();
}

}  // namespace

TriangleMesh tessellation(const CadShape& shape) {
  TriangleMesh mesh;
  mesh.vertices = shape.mesh().vertices;
  mesh.triangles = shape.mesh().triangles;
  return mesh;
}

std::string cache_settings_key(const CadModelSettings& s) { return model_settings_key(s); }

Expected<PartModel> load_part_model(const std::string& path, const CadModelSettings& settings) {
  auto shape = load_cad(path, settings.import);
  if (!shape) return shape.error();
  auto model = build_model(*shape, settings);
  if (!model) return model.error();
  auto sha256 = sha256_file(path);
  if (!sha256) return sha256.error();
  model->source_sha256 = std::move(*sha256);
  return model;
}

Expected<CachedModelLoad> load_part_model_cached(const std::string& path,
                                                 const std::string& cache_dir,
                                                 const CadModelSettings& settings) {
  auto sha256 = sha256_file(path);
  if (!sha256) return sha256.error();
  CachedModelLoad out;
  out.source_sha256 = *sha256;
  out.cache_file = (std::filesystem::path(cache_dir) / (*sha256 + ".partmodel.pb")).string();
  const std::string key = cache_settings_key(settings);
  if (auto cached = read_cache(out.cache_file, *sha256, key, settings)) {
    out.model = std::move(*cached);
    out.model.source_sha256 = *sha256;
    out.cache_hit = true;
    return out;
  }
  auto shape = load_cad(path, settings.import);
  if (!shape) return shape.error();
  auto model = build_model(*shape, settings);
  if (!model) return model.error();
  out.model = std::move(*model);
  out.model.source_sha256 = *sha256;
  std::error_code ec;
  std::filesystem::create_directories(cache_dir, ec);
  if (ec) {
    out.cache_error = cache_dir + ": " + ec.message();
    return out;
  }
  v1::CachedPartModel message = to_proto(out.model, *sha256, key);
  message.set_brep(cad_to_brep_text(*shape));
  out.cache_error = write_cache(out.cache_file, message);
  return out;
}

}  // namespace springscan::analysis
