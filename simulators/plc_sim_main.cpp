// springscan-plc-sim: a simulated PLC running the handshake for N parts against springscand and
// printing each verdict and the trigger -> RESULT_VALID latency. Like a PLC program of register
// map version 6 it re-measures an UNDECIDED part once, then routes it: good, reject or manual
// check (one "part ... route" line per part).
//   springscan-plc-sim --port 1502 --cycles 5 --parts 3,4 [--host H] [--unit N]
//                      [--word-order abcd|cdab] [--job-start J] [--serial S] [--no-heartbeat]
//                      [--timeout S]
// --serial S writes PART_SERIAL = S before every trigger (one physical part measured again).
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <sstream>
#include <string>
#include <vector>

#include "simulators/plc_client.hpp"

namespace {

using namespace springscan::simulators;

int usage(const std::string& message) {
  std::fprintf(stderr,
               "springscan-plc-sim: %s\nusage: springscan-plc-sim --port P [--host H] "
               "[--unit N] [--word-order abcd|cdab] [--cycles N] [--parts ID,ID,...] "
               "[--job-start J] [--serial S] [--no-heartbeat] [--timeout S]\n",
               message.c_str());
  return 2;
}

bool parse_int(const char* text, long lo, long hi, long& out) {
  char* end = nullptr;
  out = std::strtol(text, &end, 10);
  return end != text && *end == '\0' && out >= lo && out <= hi;
}

const char* verdict_text(const CycleResult& c) {
  switch (c.result.code) {
    case regs::ResultCode::kOk:
      return "PASS";
    case regs::ResultCode::kFormNok:
      return "FAIL (form)";
    case regs::ResultCode::kAmbiguous:
      return "FAIL (ambiguous orientation)";
    case regs::ResultCode::kUndecided:
      return "UNDECIDED";
    case regs::ResultCode::kScanFailed:
      return "NO RESULT (scan failed)";
    case regs::ResultCode::kAnalysisFailed:
      return "NO RESULT (analysis failed)";
    default:
      return "NO DATA";
  }
}

void print_cycle(int index, std::uint16_t job, std::uint16_t part, const CycleResult& c) {
  std::ostringstream bends;
  for (std::size_t j = 0; j < c.result.springback_mdeg.size(); ++j) {
    bends << (j ? " " : "") << c.result.springback_mdeg[j] / 1000.0;
  }
  std::printf(
      "cycle %d: job %u part %u: %s seq %u, max deviation %.3f mm, rms %.3f mm, "
      "springback [%s] deg, %zu vectors (%d reads); trigger->ack %.1f ms, "
      "trigger->result valid %.1f ms\n",
      index, job, part, verdict_text(c), c.result.seq, c.result.max_deviation_um / 1000.0,
      c.result.rms_deviation_um / 1000.0, bends.str().c_str(), c.result.vectors_um.size(),
      c.result.reads, c.trigger_to_ack_ms, c.trigger_to_valid_ms);
  std::fflush(stdout);
}

}  // namespace

int main(int argc, char** argv) {
  PlcClientSettings settings;
  long cycles = 1, job_start = 1, serial = 0, value = 0;
  std::vector<std::uint16_t> parts = {1};
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    const char* next = i + 1 < argc ? argv[i + 1] : nullptr;
    if (arg == "--no-heartbeat") {
      settings.send_heartbeat = false;
      continue;
    }
    if (next == nullptr) return usage(arg + " needs a value");
    ++i;
    if (arg == "--host") {
      settings.host = next;
    } else if (arg == "--port" && parse_int(next, 1, 65535, value)) {
      settings.port = static_cast<int>(value);
    } else if (arg == "--unit" && parse_int(next, 0, 255, value)) {
      settings.unit_id = static_cast<int>(value);
    } else if (arg == "--cycles" && parse_int(next, 1, 1000000, value)) {
      cycles = value;
    } else if (arg == "--job-start" && parse_int(next, 0, 65535, value)) {
      job_start = value;
    } else if (arg == "--serial" && parse_int(next, 1, 2147483647, value)) {
      serial = value;
    } else if (arg == "--timeout" && parse_int(next, 1, 3600, value)) {
      settings.step_timeout_s = static_cast<double>(value);
    } else if (arg == "--word-order" &&
               (std::strcmp(next, "abcd") == 0 || std::strcmp(next, "cdab") == 0)) {
      settings.word_order =
          std::strcmp(next, "cdab") == 0 ? regs::WordOrder::kCdab : regs::WordOrder::kAbcd;
    } else if (arg == "--parts") {
      parts.clear();
      std::stringstream list(next);
      std::string item;
      while (std::getline(list, item, ',')) {
        if (!parse_int(item.c_str(), 1, 65535, value)) return usage("bad part id '" + item + "'");
        parts.push_back(static_cast<std::uint16_t>(value));
      }
      if (parts.empty()) return usage("--parts needs at least one id");
    } else {
      return usage("bad option " + arg + " " + next);
    }
  }
  auto plc = PlcClient::connect(settings);
  if (!plc) return usage(plc.message());
  (*plc)->set_part_serial(static_cast<std::uint32_t>(serial));
  // A station just started may not have found its scanner yet (a trigger then is refused with
  // REJECT_CODE 5): a PLC program waits for SCANNER_ONLINE before its first part.
  auto online = (*plc)->wait_for(
      [](const StationStatus& s) { return s.bit(regs::kDiScannerOnline); }, "SCANNER_ONLINE = 1");
  if (!online) return usage(online.message());
  int failures = 0;
  for (long k = 0; k < cycles; ++k) {
    const auto job = static_cast<std::uint16_t>((job_start + k) & 0xFFFF);
    const std::uint16_t part = parts[static_cast<std::size_t>(k) % parts.size()];
    auto inspected = (*plc)->inspect_part(job, part);
    if (!inspected) {
      std::printf("cycle %ld: job %u part %u: ERROR %s\n", k + 1, job, part,
                  inspected.message().c_str());
      return 1;
    }
    for (const CycleResult& cycle : inspected->cycles) {
      if (!cycle.accepted) {
        std::printf("cycle %ld: job %u part %u: trigger REFUSED, REJECT_CODE %u\n", k + 1, job,
                    part, static_cast<unsigned>(cycle.reject_code));
        ++failures;
        continue;
      }
      print_cycle(static_cast<int>(k + 1), job, part, cycle);
      if (cycle.error_code != 0) {
        std::printf("  station ERROR_CODE %u: sending ERROR_RESET\n", cycle.error_code);
        auto reset = (*plc)->reset_errors();
        if (!reset) return usage(reset.message());
      }
    }
    std::printf("part %ld: job %u part %u: %zu measurement(s), route %s\n", k + 1, job, part,
                inspected->cycles.size(), to_string(inspected->route));
    std::fflush(stdout);
  }
  return failures == 0 ? 0 : 1;
}
