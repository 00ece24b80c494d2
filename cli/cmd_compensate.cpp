// springscan compensate: the compensated die surface as STEP (DESIGN.md "Compensated die
// surface", docs/matching.md "Compensated CAD").
#include <google/protobuf/util/json_util.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <optional>
#include <system_error>

#include "analysis/cad/compensated_solid.hpp"
#include "analysis/cad/import.hpp"
#include "analysis/cad/segmentation.hpp"
#include "analysis/io/file_io.hpp"
#include "analysis/io/sha256.hpp"
#include "analysis/matching/field_evaluation.hpp"
#include "analysis/messages/matching_proto.hpp"
#include "cli/cli_common.hpp"

namespace springscan::cli {
namespace {

namespace fs = std::filesystem;
constexpr const char* kName = "compensate";

// REPORT: report.pb, report.json, or a folder holding report.pb (an `analyze --out` folder or a
// record r<N>/ of the daemon's report store).
analysis::Expected<v1::InspectionReport> load_report(fs::path path) {
  std::error_code ec;
  if (fs::is_directory(path, ec)) path /= "report.pb";
  auto bytes = analysis::read_file_bytes(path.string());
  if (!bytes) return bytes.error();
  v1::InspectionReport report;
  if (path.extension() == ".json") {
    const auto status = google::protobuf::util::JsonStringToMessage(*bytes, &report);
    if (!status.ok())
      return analysis::fail(
          analysis::ErrorCode::kCorruption,
          path.string() + ": not an InspectionReport in JSON: " + std::string(status.message()));
  } else if (!report.ParseFromString(*bytes)) {
    return analysis::fail(analysis::ErrorCode::kCorruption,
                          path.string() + ": not a binary InspectionReport (" +
                              std::to_string(bytes->size()) + " bytes)");
  }
  return report;
}

// The report must be of this CAD: the SHA-256 of the CAD file's bytes it records.
analysis::Expected<bool> check_same_part(const v1::InspectionReport& report, const std::string& cad,
                                         const Logger& log) {
  const auto sha = analysis::sha256_file(cad);
  if (!sha) return sha.error();
  const auto& in = report.input();
  if (in.cad_sha256().empty()) {
    log.warning("the report records no CAD SHA-256: cannot check that it is of " + cad);
    return true;
  }
  if (in.cad_sha256() == *sha) return true;
  return analysis::fail("the report is of another part: it was made with CAD '" + in.cad_file() +
                        "' (part id '" + in.part_id() + "', SHA-256 " +
                        in.cad_sha256().substr(0, 16) + "...), but " + cad + " has SHA-256 " +
                        sha->substr(0, 16) + "...");
}

// The translations the scan did not fix (report global_fit.free_directions): the field's
// component along them is the alignment's, not the part's (field_evaluation.hpp).
analysis::FieldEvaluationSettings field_settings(const v1::InspectionReport& report) {
  analysis::FieldEvaluationSettings settings;
  for (const auto& free : report.global_fit().free_directions()) {
    const analysis::Vec3 d(free.direction().x(), free.direction().y(), free.direction().z());
    if (d.norm() > 0.5) settings.free_directions.push_back(d.normalized());
  }
  return settings;
}

// -F x the field at each point (docs/matching.md: the displacement adjustment method).
analysis::OffsetField offsets(const analysis::DeformationField& field,
                              const analysis::FieldEvaluationSettings& settings, double factor) {
  return [&field, settings, factor](const std::vector<analysis::Vec3>& points) {
    auto at = analysis::evaluate_field(field, points, settings);
    analysis::PointOffsets out;
    out.offset.reserve(points.size());
    for (const auto& d : at.deformation) out.offset.push_back(-factor * d);
    out.covered = std::move(at.covered);
    // The field's scatter, scaled like the offsets: the allowance of a plane or cylinder.
    for (const double u : at.spread_mm) out.uncertainty_mm.push_back(factor * u);
    return out;
  };
}

void print_summary(const analysis::CompensatedShape& c, const std::string& out) {
  int planes = 0, cylinders = 0, bsplines = 0;
  for (const auto& f : c.faces) {
    planes += f.surface == "plane";
    cylinders += f.surface == "cylinder";
    bsplines += f.surface == "bspline";
  }
  char line[480];
  std::snprintf(line, sizeof line,
                "wrote %s: %zu faces (%d planes, %d cylinders, %d B-splines), valid solid/shell "
                "(BRepCheck_Analyzer)\nlargest displacement %.4f mm; refit deviation from the "
                "moved samples: max %.5f mm, p95 %.5f mm; field uncertainty up to %.4f mm; "
                "largest edge tolerance %.4f mm\n",
                out.c_str(), c.faces.size(), planes, cylinders, bsplines, c.max_offset_mm,
                c.max_deviation_mm, c.p95_deviation_mm, c.max_uncertainty_mm, c.max_tolerance_mm);
  std::cout << line;
}

// The die as `springscan model` and the simulator will read it back: the same flanges and bends
// as the CAD it moved, or a warning that names what is lost. A real form defect (curl, twist)
// compensated into B-spline faces loses its flanges rightly, so this warns rather than refuses;
// a field too sparse or noisy for its flanges to stay planes loses them too (docs/matching.md).
void report_reimport(const analysis::CadShape& die, const analysis::CadShape& compensated,
                     const Logger& log) {
  const auto before = analysis::segment_cad(die);
  const auto after = analysis::segment_cad(compensated);
  const std::string counts = std::to_string(after.flanges.size()) + " flanges and " +
                             std::to_string(after.bends.size()) + " bends";
  if (after.flanges.size() == before.flanges.size() && after.bends.size() == before.bends.size()) {
    std::cout << "re-imports with " << counts << ", as the CAD\n";
    return;
  }
  log.warning("the compensated die re-imports with " + counts + " where the CAD has " +
              std::to_string(before.flanges.size()) + " and " +
              std::to_string(before.bends.size()) +
              ": faces that did not stay planes or cylinders are B-splines (a real curl, or a "
              "field too sparse or noisy for them: a denser scan, or --canonical-tolerance); "
              "springscan model and a press simulation will not see those flanges and bends");
}

}  // namespace

int compensate_main(int argc, char** argv) {
  ArgParser args(kName, "springscan compensate --cad PART.step --report REPORT --out DIE.step",
                 "Moves every face of the CAD by -F x the deformation field the report measured "
                 "(displacement adjustment) and writes the compensated die surface as STEP: "
                 "faces that stay planes or cylinders as such, the others as B-spline faces, in "
                 "one valid solid or shell. REPORT is report.pb, report.json or a folder holding "
                 "report.pb (springscan analyze --out, or a record of the daemon's report store); "
                 "it must be a report of PART (its CAD SHA-256). To iterate, pass the die of the "
                 "last round as --die and the report of the part it produced.");
  args.add_option("cad", "PART", "the CAD the report was made with (IGES, STEP or BRep)");
  args.add_option("report", "REPORT", "the inspection report with the deformation field");
  args.add_option("out", "DIE.step", "where to write the compensated CAD (STEP)");
  args.add_option("factor", "F", "compensation factor F (default 1)");
  args.add_option("die", "DIE", "the die surface to move (default: --cad)");
  args.add_option("canonical-tolerance", "MM",
                  "a moved plane or cylinder within this stays one (default 0.1)");
  Logger log;
  if (auto exit_code = args.start(argc, argv, log)) return *exit_code;
  for (const char* required : {"cad", "report", "out"})
    if (!args.has(required))
      return fail_with(kName, std::string("--") + required + " is required", kExitUsage);
  const auto factor = args.has("factor") ? args.get_number("factor") : std::optional(1.0);
  if (!factor || !std::isfinite(*factor) || *factor <= 0.0 || *factor > 3.0)
    return fail_with(kName, "--factor " + args.get("factor") + ": expected a number in (0, 3]",
                     kExitUsage);
  const std::string out = args.get("out");
  const std::string ext = fs::path(out).extension().string();
  if (ext != ".step" && ext != ".stp" && ext != ".STEP" && ext != ".STP")
    return fail_with(kName, "--out " + out + ": expected a .step or .stp file", kExitUsage);
  auto report = load_report(args.get("report"));
  if (!report) return fail_with(kName, report.message(), kExitUsage);
  if (auto same = check_same_part(*report, args.get("cad"), log); !same)
    return fail_with(kName, same.message(), kExitUsage);
  auto field = analysis::from_proto(report->deformation_field());
  if (!field) return fail_with(kName, field.message(), kExitUsage);
  if (field->vectors.empty())
    return fail_with(kName, args.get("report") + ": the report holds no deformation field",
                     kExitUsage);
  analysis::CompensatedShapeSettings settings;
  if (args.has("canonical-tolerance")) {
    const auto mm = args.get_number("canonical-tolerance");
    if (!mm || !(*mm >= 0.0) || *mm > 1.0)
      return fail_with(
          kName,
          "--canonical-tolerance " + args.get("canonical-tolerance") + ": expected 0 to 1 mm",
          kExitUsage);
    settings.canonical_tolerance_mm = *mm;
  }
  const std::string die_path = args.has("die") ? args.get("die") : args.get("cad");
  const auto die = analysis::load_cad(die_path);
  if (!die) return fail_with(kName, die.message(), kExitUsage);
  const auto compensated = analysis::compensated_shape(
      *die, offsets(*field, field_settings(*report), *factor), settings);
  if (!compensated)
    return fail_with(kName, die_path + ": " + compensated.message(),
                     compensated.error().is_invalid_input() ? kExitUsage : kExitAnalysisFailed);
  if (auto written = analysis::write_step_atomically(compensated->shape, out); !written)
    return fail_with(kName, written.message(), kExitAnalysisFailed);
  for (const auto& f : compensated->faces)
    log.debug("face " + std::to_string(f.id) + ": " + f.surface + ", refit deviation " +
              std::to_string(f.max_deviation_mm) + " mm, largest displacement " +
              std::to_string(f.max_offset_mm) + " mm, field coverage " +
              std::to_string(f.coverage));
  print_summary(*compensated, out);
  report_reimport(*die, compensated->shape, log);
  return kExitOk;
}

}  // namespace springscan::cli
