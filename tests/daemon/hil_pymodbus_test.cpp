// Hardware in the loop with a third-party PLC client (hil_rig.hpp): tests/daemon/pymodbus_plc.py,
// written from docs/modbus-register-map.md alone with Debian's python3-pymodbus, drives the
// whole handshake against the real springscand under the emulated scanner. What it read from
// the registers is compared here with the reports the daemon stored.
#include <cstdio>
#include <sstream>

#include "hil_rig.hpp"
#include "tests/support/test_paths.hpp"

namespace springscan::daemon {
namespace {

using testing::HilTest;

struct Collected {
  int seq = 0, job = 0, code = -1, n = -1, bends = -1, max_dev_um = 0;
};

/// The script's "RESULT seq=... job=... part=... code=... n=... bends=... max_dev_um=..." lines.
std::vector<Collected> collected(const std::string& output) {
  std::vector<Collected> out;
  std::istringstream lines(output);
  std::string line;
  while (std::getline(lines, line)) {
    Collected c;
    int part = 0;
    if (std::sscanf(line.c_str(),
                    "RESULT seq=%d job=%d part=%d code=%d n=%d bends=%d max_dev_um=%d", &c.seq,
                    &c.job, &part, &c.code, &c.n, &c.bends, &c.max_dev_um) == 7) {
      out.push_back(c);
    }
  }
  return out;
}

TEST_F(HilTest, PymodbusClientWrittenFromTheDocRunsTheWholeHandshake) {
  if (testing::run_command(std::string(springscan::test_paths::kPython3) + " -c 'import pymodbus'")
          .first != 0) {
    GTEST_SKIP() << "python3-pymodbus is not installed (scripts/install-deps.sh)";
  }
  emulate(testing::kGoodSpringback);
  auto daemon = start_daemon();
  const auto [status, output] = testing::run_command(
      std::string(springscan::test_paths::kPython3) + " " +
      springscan::test_paths::source("tests/daemon/pymodbus_plc.py") + " --port " +
      std::to_string(daemon->port()) + " --cycles 2 --job 300 --part 1");
  ASSERT_EQ(status, 0) << output;
  EXPECT_NE(output.find("\nOK"), std::string::npos) << output;
  const std::vector<Collected> results = collected(output);
  ASSERT_EQ(results.size(), 3u) << output;  // two cycles and the one collected after the outage
  for (std::size_t k = 0; k < results.size(); ++k) {
    const Collected& c = results[k];
    EXPECT_EQ(c.seq, static_cast<int>(k + 1));
    EXPECT_EQ(c.job, 300 + static_cast<int>(k));
    const v1::InspectionReport r = report(c.seq);  // what the station stored for that result
    EXPECT_EQ(c.code, static_cast<int>(r.result_code()));
    EXPECT_EQ(r.input().part_serial(), std::to_string(70000 + c.job));  // PART_SERIAL, 2 words
    EXPECT_EQ(c.n, std::min(r.compensation_size(), static_cast<int>(regs::kMaxVectors)));
    EXPECT_GT(c.n, 0);
    EXPECT_EQ(c.bends, r.bends_size());
    EXPECT_EQ(c.max_dev_um, regs::mm_to_um(std::max(std::abs(r.deviation().min()),
                                                    std::abs(r.deviation().max()))));
  }
  EXPECT_EQ(record_count(), 3);  // one result per accepted trigger: none lost, none duplicated
  EXPECT_EQ(daemon->stop(SIGTERM), 0);
}

}  // namespace
}  // namespace springscan::daemon
