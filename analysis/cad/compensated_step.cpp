// STEP output of a CadShape, atomic (compensated_solid.hpp write_step_atomically).
#include <unistd.h>

#include <IFSelect_ReturnStatus.hxx>
#include <Interface_Static.hxx>
#include <STEPControl_Writer.hxx>
#include <Standard_Failure.hxx>
#include <filesystem>
#include <system_error>

#include "analysis/cad/compensated_solid.hpp"
#include "analysis/cad/internal.hpp"
#include "analysis/io/file_io.hpp"

namespace springscan::analysis {

Expected<bool> write_step_atomically(const CadShape& shape, const std::string& path) {
  namespace fs = std::filesystem;
  if (shape.empty()) return fail(path + ": nothing to write (empty shape)");
  // OpenCASCADE writes to a path only: a scratch file beside the target, whose bytes then go
  // through the one atomic writer (fsync, rename); the scratch file never stays behind.
  const fs::path target(path);
  std::string scratch_name = ".";
  scratch_name += target.filename().string();
  scratch_name += ".occt-" + std::to_string(::getpid()) + ".step";
  const fs::path scratch = target.parent_path() / scratch_name;
  struct Remove {
    fs::path file;
    ~Remove() {
      std::error_code ec;
      fs::remove(file, ec);
    }
  } remove{scratch};
  try {
    const std::lock_guard<std::mutex> lock(occt_exchange_mutex());
    STEPControl_Writer writer;
    Interface_Static::SetCVal("write.step.unit", "MM");
    Interface_Static::SetCVal("write.step.schema", "AP214IS");
    if (writer.Transfer(shape.impl().shape, STEPControl_AsIs) != IFSelect_RetDone)
      return fail(ErrorCode::kAnalysisFailed, path + ": the shape could not be translated to STEP");
    if (writer.Write(scratch.c_str()) != IFSelect_RetDone)
      return fail(ErrorCode::kIoError,
                  path + ": could not write the STEP file (" + scratch.string() + ")");
  } catch (const Standard_Failure& e) {
    return fail(ErrorCode::kAnalysisFailed, describe_occt_failure(path, e.GetMessageString()));
  }
  auto bytes = read_file_bytes(scratch.string());
  if (!bytes) return bytes.error();
  return write_file_atomically(path, *bytes);
}

}  // namespace springscan::analysis
