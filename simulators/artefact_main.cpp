// springscan-artefact: writes the station's calibration artefact (simulators/parts/artefact.hpp)
// as STEP and, with --scans, each demo head's raw scan of it (simulators/parts/head_scan.hpp:
// the heads mounted 0.5 degree and 2 mm off their drawing, an encoder scale error) with the truth,
// for `springscan calibrate` (docs/calibration.md).
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>

#include "analysis/cad/model.hpp"
#include "analysis/io/point_io.hpp"
#include "simulators/parts/artefact.hpp"
#include "simulators/parts/head_scan.hpp"

namespace {

using namespace springscan;

int usage() {
  std::fprintf(stderr,
               "usage: springscan-artefact --out DIR [--scans] [--motion-scale K]\n"
               "  writes DIR/calibration-artefact.step; with --scans also DIR/head-a.ply,\n"
               "  head-b.ply, head-c.ply (raw head frames: x, z range, encoder) and\n"
               "  DIR/truth.txt (each head's true transform, the encoder scale K, default "
               "1.002)\n");
  return 2;
}

void write_truth(std::ofstream& out, const parts::DemoHead& head, double scale) {
  out << "head " << head.name << " motion_scale " << scale << " transform";
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) out << ' ' << head.truth.matrix()(r, c);
  out << '\n';
}

int write_scans(const std::string& dir, const std::string& step, double scale) {
  auto model = analysis::load_part_model(step);
  if (!model) return std::fprintf(stderr, "%s\n", model.message().c_str()), 1;
  std::ofstream truth(dir + "/truth.txt");
  truth.precision(12);
  std::uint64_t seed = 1;
  for (const parts::DemoHead& head : parts::demo_heads()) {
    auto scan = parts::head_scan(model->mesh, parts::demo_head_scan(head.truth, scale, seed++));
    if (!scan) return std::fprintf(stderr, "%s\n", scan.message().c_str()), 1;
    const std::string path = dir + "/head-" + head.name + ".ply";
    auto written = analysis::write_point_cloud(path, *scan);
    if (!written) return std::fprintf(stderr, "%s\n", written.message().c_str()), 1;
    write_truth(truth, head, scale);
    std::printf("%s: %zu points\n", path.c_str(), scan->points.size());
  }
  return truth.good() ? 0 : 1;
}

}  // namespace

int main(int argc, char** argv) {
  std::string dir;
  bool scans = false;
  double scale = 1.002;
  for (int i = 1; i < argc; ++i) {
    if (std::strcmp(argv[i], "--out") == 0 && i + 1 < argc) {
      dir = argv[++i];
    } else if (std::strcmp(argv[i], "--scans") == 0) {
      scans = true;
    } else if (std::strcmp(argv[i], "--motion-scale") == 0 && i + 1 < argc) {
      scale = std::atof(argv[++i]);
    } else {
      return usage();
    }
  }
  if (dir.empty() || !(scale > 0.0)) return usage();
  std::filesystem::create_directories(dir);
  const std::string step = dir + "/calibration-artefact.step";
  auto written = parts::write_artefact_step(step);
  if (!written) return std::fprintf(stderr, "%s\n", written.message().c_str()), 1;
  std::printf("%s\n", step.c_str());
  return scans ? write_scans(dir, step, scale) : 0;
}
