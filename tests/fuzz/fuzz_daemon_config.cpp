// libFuzzer target: the daemon's config file (protobuf text format plus our validation with
// file:line messages). Any text must give settings or a clear error; nothing it names is read
// here (paths are only resolved, CAD files are loaded later).
#include <cstddef>
#include <cstdint>
#include <string>

#include "daemon/config.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  (void)springscan::daemon::parse_daemon_config(text, "/fuzz/springscand.textproto");
  return 0;
}
