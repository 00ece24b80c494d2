#pragma once
// A value or an error: how expected failures (bad input, too few points, no convergence, a
// device that went away) come back from library code, which neither prints nor aborts
// (STYLE.md §5). An error is a code plus a message, like leveldb's Status: callers branch on
// the code (`error.code`, `is_not_found()`, a switch), people read the message. Nothing decides
// by searching the text of a message.

#include <cstdint>
#include <string>
#include <string_view>
#include <utility>
#include <variant>

namespace springscan::analysis {

/// What kind of failure an Error is. One enum for every layer, analysis and drivers alike:
/// failures cross the Scanner interface and the analysis pipeline as the same Error type, and
/// analysis/core cannot see a driver header, so the device codes live here too (leveldb's
/// Status carries IOError beside Corruption the same way). The USB transport keeps its own
/// libusb buckets (drivers::UsbError) and maps them onto these at the driver boundary.
///
/// Values are stable (they appear in logs): add new ones inside their group, never renumber.
enum class ErrorCode : std::uint8_t {
  // --- input, files, settings ---
  /// The input was refused: a bad argument or value (empty scan, NaN point, wrong units).
  /// The default of `fail(message)`: most existing call sites validate their input.
  kInvalidInput = 1,
  kNotFound = 2,         ///< a file, part or device that is not there
  kIoError = 3,          ///< a file exists but cannot be read or written (permissions, disk)
  kCorruption = 4,       ///< a file's content is malformed or truncated (bad PLY, STEP, .pb)
  kInvalidSettings = 5,  ///< a settings or config field out of range (names field and value)
  kAnalysisFailed = 6,   ///< the method could not produce a result: too few points, no fit
  kCancelled = 7,        ///< the caller asked to stop (progress callback, shutdown)
  // --- devices (drivers/, docs/device-protocol.md §7) ---
  kDeviceGone = 20,       ///< the device was unplugged or vanished (LIBUSB_ERROR_NO_DEVICE)
  kTimeout = 21,          ///< the device stopped answering within the timeout
  kStalledEndpoint = 22,  ///< an endpoint stalled (STALL) and could not be cleared
  kBadCrc = 23,           ///< a frame failed its CRC (§2.2)
  kSequenceGap = 24,      ///< frames or data records lost or out of order (§2.5, §4)
  kProtocolError = 25,    ///< the device broke the protocol: unexpected frame, bad payload
  kDeviceFault = 26,      ///< the device reported an error frame (§5): sensor fault, overrun
  kOsError = 27,          ///< any other OS or libusb failure (access, busy, overflow, I/O)
  // --- bugs ---
  kInternal = 99,  ///< a broken invariant: a bug, see the log
};

/// The code's name as a short lower-case phrase ("not found", "bad CRC").
std::string to_string(ErrorCode code);

/// An error that the caller can show as one line (what failed, where, and the value seen) and
/// branch on by its code. `message` comes first so that `Error{"text"}` still works.
struct Error {
  std::string message;
  ErrorCode code = ErrorCode::kInvalidInput;

  bool is_invalid_input() const { return code == ErrorCode::kInvalidInput; }
  bool is_not_found() const { return code == ErrorCode::kNotFound; }
  bool is_io_error() const { return code == ErrorCode::kIoError; }
  bool is_corruption() const { return code == ErrorCode::kCorruption; }
  bool is_invalid_settings() const { return code == ErrorCode::kInvalidSettings; }
  bool is_analysis_failed() const { return code == ErrorCode::kAnalysisFailed; }
  bool is_cancelled() const { return code == ErrorCode::kCancelled; }
  bool is_device_gone() const { return code == ErrorCode::kDeviceGone; }
  bool is_timeout() const { return code == ErrorCode::kTimeout; }

  /// The same error with `context` in front of the message (the code is kept):
  /// `return model.error().prepend("part 3: ");`
  Error prepend(std::string_view context) const {
    return Error{std::string(context) + message, code};
  }
  /// "not found: scan.ply: no such file": the code's name, then the message.
  std::string to_string() const { return analysis::to_string(code) + ": " + message; }
};

/// Holds either a T or an Error. Check `ok()` (or `if (result)`) before `value()`.
template <typename T>
class Expected {
 public:
  Expected(T value) : state_(std::move(value)) {}      // NOLINT: implicit by design
  Expected(Error error) : state_(std::move(error)) {}  // NOLINT: implicit by design

  bool ok() const { return std::holds_alternative<T>(state_); }
  explicit operator bool() const { return ok(); }

  T& value() & { return std::get<T>(state_); }
  const T& value() const& { return std::get<T>(state_); }
  T&& value() && { return std::get<T>(std::move(state_)); }
  T* operator->() { return &value(); }
  const T* operator->() const { return &value(); }
  T& operator*() & { return value(); }
  const T& operator*() const& { return value(); }

  const Error& error() const { return std::get<Error>(state_); }
  const std::string& message() const { return error().message; }
  ErrorCode code() const { return error().code; }

 private:
  std::variant<T, Error> state_;
};

/// Shorthand for returning an error of code kInvalidInput (the default: most call sites
/// refuse a bad input): `return fail("scan.ply: line 12: bad vertex");`
inline Error fail(std::string message) { return Error{std::move(message)}; }
/// Shorthand for returning an error with a code: `return fail(ErrorCode::kNotFound, path);`
inline Error fail(ErrorCode code, std::string message) { return Error{std::move(message), code}; }

inline std::string to_string(ErrorCode code) {
  switch (code) {
    case ErrorCode::kInvalidInput:
      return "invalid input";
    case ErrorCode::kNotFound:
      return "not found";
    case ErrorCode::kIoError:
      return "I/O error";
    case ErrorCode::kCorruption:
      return "corrupt input";
    case ErrorCode::kInvalidSettings:
      return "invalid settings";
    case ErrorCode::kAnalysisFailed:
      return "analysis failed";
    case ErrorCode::kCancelled:
      return "cancelled";
    case ErrorCode::kDeviceGone:
      return "device gone";
    case ErrorCode::kTimeout:
      return "timeout";
    case ErrorCode::kStalledEndpoint:
      return "endpoint stalled";
    case ErrorCode::kBadCrc:
      return "bad CRC";
    case ErrorCode::kSequenceGap:
      return "sequence gap";
    case ErrorCode::kProtocolError:
      return "protocol error";
    case ErrorCode::kDeviceFault:
      return "device fault";
    case ErrorCode::kOsError:
      return "OS error";
    case ErrorCode::kInternal:
      return "internal error";
  }
  return "unknown error";
}

}  // namespace springscan::analysis
