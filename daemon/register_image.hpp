#pragma once
// The register image the Modbus server serves: a libmodbus mapping laid out as
// daemon/register_map.hpp says, filled from the state machine's status and the result block.
// Owned by the event loop thread, which is also the only thread serving Modbus requests, so a
// read never sees half of an update (register map "Handshake" step 4).

#include <modbus/modbus.h>

#include <cstdint>
#include <memory>

#include "daemon/register_map.hpp"
#include "daemon/result_block.hpp"
#include "daemon/state_machine.hpp"

namespace springscan::daemon {

/// Live values that are not part of the machine status.
struct LiveValues {
  std::uint16_t boot_id = 1;
  std::uint16_t heartbeat = 0;
  std::uint16_t scan_progress_pct = 0;
  bool calibration_drift = false;  ///< CALIBRATION_DRIFT: latched by the station
};

class RegisterImage {
 public:
  /// Allocates the mapping; throws std::bad_alloc if libmodbus cannot.
  explicit RegisterImage(regs::WordOrder order);

  /// The mapping for modbus_reply. Valid for the lifetime of this object.
  modbus_mapping_t* mapping() { return mapping_.get(); }
  regs::WordOrder word_order() const { return order_; }

  /// The PLC's values: coils OR-ed with CONTROL_WORD bits, and the holding registers 1..3.
  PlcControl plc_control() const;
  /// Writes the discrete inputs, the live block, the status word and their FC03 mirror.
  void publish_status(const MachineStatus& status, const LiveValues& live);
  /// Writes the frozen result block and the vector block (data first, RESULT_SEQ last), then
  /// refreshes the window and the FC03 mirror. Entries past the block's rows are zeroed.
  void publish_result(const ResultBlock& block);
  /// Refreshes the paged window (800..921) for the page in PAGE_SELECT.
  void refresh_window();

  std::uint16_t input_register(std::uint16_t address) const;
  std::uint16_t holding_register(std::uint16_t address) const;
  bool discrete_input(std::uint16_t address) const;

 private:
  void put_int32(std::uint16_t address, std::int32_t value);
  void mirror_inputs(std::uint16_t first, std::uint16_t count, std::uint16_t holding_first);

  struct MappingDeleter {
    void operator()(modbus_mapping_t* m) const { modbus_mapping_free(m); }
  };
  std::unique_ptr<modbus_mapping_t, MappingDeleter> mapping_;
  regs::WordOrder order_;
};

}  // namespace springscan::daemon
