// libFuzzer target: the Modbus request check the server runs on every frame before libmodbus
// sees it: the MBAP prefix, then the whole ADU. Whatever the bytes, the check must answer
// (valid, an exception, or a frame to close on) without reading past `size`.
#include <cstddef>
#include <cstdint>

#include "daemon/request_check.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace springscan::daemon;
  const FrameHeader header = check_mbap_prefix(data, size);
  if (header.valid && header.frame_bytes <= size) {
    (void)check_request(data, header.frame_bytes, RequestCheckSettings{});
  }
  (void)check_request(data, size, RequestCheckSettings{});
  return 0;
}
