#pragma once
// The PLC register map of springscand: every address, bit, code and encoding, in one header
// shared by the daemon and the PLC simulator (STYLE.md section 7). docs/modbus-register-map.md
// is the same map written for a PLC programmer; change both together and bump kMapVersion.
//
// Addresses are Modbus PDU addresses (0-based, as on the wire). mbpoll and most PLC
// configuration tools count from 1: PDU address 100 is "input register 30101" there.
// All addresses are below 9999 so PLCs limited to five-digit references reach every value.
//
// Deviation from ../shared/reference/plc-usb-reliability-notes.md section 1 (the proposed
// map): the paged window is at 800..921, not 900..1021, because 902..1021 would overlap the
// flat vector block that starts at 1000. Also added: the bend table (springback per bend, the
// issue asks for it in the frozen block), a status word and a reject code (for PLCs that read
// registers only), and read-only holding-register mirrors of the input registers (for PLCs
// limited to FC03).

#include <cstddef>
#include <cstdint>
#include <limits>

namespace springscan::daemon::regs {

// 2: ERROR_RESET keeps a valid result, RESULT_STALE (discrete input 10) instead of the TTL
// dropping RESULT_VALID, PLC_COMM_LOST raises ERROR_CODE 7, PAGE_SELECT past the last page and
// unit id 0 as below, ERROR_DETAIL 5..8 (stalled endpoint, sequence gap, protocol error, device
// fault), which version 1 reported as 9.
// 4: CALIBRATION_DRIFT (discrete input 11, status word bit 11), from the check part (issue 42).
// 5: PART_SERIAL (holding 5-6), the individual part's serial for the gauge studies (issue 42).
// 6: the undecided part (issue 41, docs/uncertainty.md): RESULT_CODE 6 UNDECIDED, PART_UNDECIDED
// (discrete input 12, status word bit 12), bend flag UNDECIDED, BENDS_UNDECIDED at 119 (was
// reserved, 0). An UNDECIDED part is never PART_OK: a PLC program of version 5 stays safe.
inline constexpr std::uint16_t kMapVersion = 6;

// ------------------------------------------------------------------------------------------
// Coils (FC01 read, FC05/FC15 write): PLC -> station.
inline constexpr std::uint16_t kCoilTriggerEnable = 0;  ///< level: triggers are accepted
inline constexpr std::uint16_t kCoilTrigger = 1;        ///< rising edge starts an inspection
inline constexpr std::uint16_t kCoilResultAck = 2;      ///< rising edge clears RESULT_VALID
inline constexpr std::uint16_t kCoilErrorReset = 3;     ///< rising edge clears errors / FAULT
inline constexpr std::uint16_t kCoilCount = 4;

// ------------------------------------------------------------------------------------------
// Discrete inputs (FC02 read): station -> PLC.
inline constexpr std::uint16_t kDiReady = 0;        ///< a trigger now would be accepted
inline constexpr std::uint16_t kDiTriggerAck = 1;   ///< trigger accepted; drops after TRIGGER
inline constexpr std::uint16_t kDiBusy = 2;         ///< an inspection is running
inline constexpr std::uint16_t kDiResultValid = 3;  ///< the frozen result block is new
inline constexpr std::uint16_t kDiPartOk = 4;       ///< the result's verdict (valid only with 3)
inline constexpr std::uint16_t kDiError = 5;        ///< ERROR_CODE != 0; clear with ERROR_RESET
inline constexpr std::uint16_t kDiTriggerRejected = 6;  ///< last trigger edge refused (REJECT_CODE)
inline constexpr std::uint16_t kDiScannerOnline = 7;    ///< the scanner is present and open
inline constexpr std::uint16_t kDiHeartbeat = 8;        ///< toggles every second
inline constexpr std::uint16_t kDiPlcCommLost = 9;      ///< PLC_HEARTBEAT went silent (latched)
inline constexpr std::uint16_t kDiResultStale = 10;  ///< RESULT_VALID unacknowledged > result_ttl_s
/// The check part was beyond a reference limit (latched until a check part passes; the PLC holds
/// production until the heads are recalibrated, docs/calibration.md).
inline constexpr std::uint16_t kDiCalibrationDrift = 11;
/// The result's part could not be decided (RESULT_CODE 6; valid only with RESULT_VALID, cleared
/// with it): re-measure once, then route the part to a manual check. PART_OK is 0 then.
inline constexpr std::uint16_t kDiPartUndecided = 12;
inline constexpr std::uint16_t kDiCount = 13;

// ------------------------------------------------------------------------------------------
// Holding registers (FC03 read, FC06/FC16 write). 0..6 are written by the PLC; the mirrors
// below are read-only (a write answers exception 02 ILLEGAL DATA ADDRESS).
inline constexpr std::uint16_t kHrControlWord = 0;   ///< bit i = coil i (OR-ed with the coils)
inline constexpr std::uint16_t kHrJobId = 1;         ///< latched at the trigger edge
inline constexpr std::uint16_t kHrPartId = 2;        ///< latched at the trigger edge
inline constexpr std::uint16_t kHrPlcHeartbeat = 3;  ///< the PLC changes it at least every 1 s
inline constexpr std::uint16_t kHrPageSelect = 4;    ///< page shown in the window at 800
/// The individual part's serial (uint32 in the map's word order, 0: none), latched at the
/// trigger edge into the report's input.part_serial: the type-3 gauge study groups by it.
inline constexpr std::uint16_t kHrPartSerial = 5;
inline constexpr std::uint16_t kHrWritableCount = 7;
/// Holding 10..(10+kLiveCount) mirror input registers 0..kLiveCount (read-only).
inline constexpr std::uint16_t kHrLiveMirror = 10;
/// Holding registers at or above 100 mirror the input registers at the same address.
inline constexpr std::uint16_t kHrResultMirror = 100;

// ------------------------------------------------------------------------------------------
// Input registers (FC04 read): live block, refreshed every loop iteration.
inline constexpr std::uint16_t kIrMapVersion = 0;
inline constexpr std::uint16_t kIrBootId = 1;         ///< random at every start, never 0
inline constexpr std::uint16_t kIrState = 2;          ///< State below (PackML-like)
inline constexpr std::uint16_t kIrHeartbeat = 3;      ///< +1 every 100 ms, wraps
inline constexpr std::uint16_t kIrErrorCode = 4;      ///< ErrorCode below
inline constexpr std::uint16_t kIrErrorDetail = 5;    ///< ErrorDetail below
inline constexpr std::uint16_t kIrTriggerCount = 6;   ///< accepted triggers since start, wraps
inline constexpr std::uint16_t kIrEndianProbe = 7;    ///< 7..8: int32 0x01020304 in WORD_ORDER
inline constexpr std::uint16_t kIrStatusWord = 9;     ///< bit i = discrete input i
inline constexpr std::uint16_t kIrRejectCode = 10;    ///< RejectCode of the last refused trigger
inline constexpr std::uint16_t kIrRejectCount = 11;   ///< refused triggers since start, wraps
inline constexpr std::uint16_t kIrScanProgress = 12;  ///< 0..100 % of the running scan
inline constexpr std::uint16_t kLiveCount = 13;
inline constexpr std::int32_t kEndianProbeValue = 0x01020304;

// Input registers: the frozen result block. Written only when an inspection ends, before
// RESULT_VALID rises; unchanged until the next result (a PLC may read it in several requests).
inline constexpr std::uint16_t kIrResultSeq = 100;     ///< 1..65535, never 0 once a result exists
inline constexpr std::uint16_t kIrResultPartId = 101;  ///< PART_ID echo
inline constexpr std::uint16_t kIrResultJobId = 102;   ///< JOB_ID echo
inline constexpr std::uint16_t kIrResultCode = 103;    ///< ResultCode below
inline constexpr std::uint16_t kIrMaxDeviation = 104;  ///< 104..105 int32 um, max |deviation|
inline constexpr std::uint16_t kIrRmsDeviation = 106;  ///< 106..107 int32 um
inline constexpr std::uint16_t kIrVectorCount = 108;   ///< N compensation vectors (<= 1024)
inline constexpr std::uint16_t kIrVectorRecordSize = 109;
inline constexpr std::uint16_t kIrCycleTimeMs = 110;  ///< 110..111 int32 ms, trigger -> result
inline constexpr std::uint16_t kIrBendCount = 112;    ///< bends in the table (<= 16)
inline constexpr std::uint16_t kIrBendRecordSize = 113;
inline constexpr std::uint16_t kIrBendsFailed = 114;     ///< bends out of angle tolerance (by > U)
inline constexpr std::uint16_t kIrP95Deviation = 115;    ///< 115..116 int32 um, 95th pct |dev|
inline constexpr std::uint16_t kIrScanPoints = 117;      ///< 117..118 int32 points scanned
inline constexpr std::uint16_t kIrBendsUndecided = 119;  ///< bends UNDECIDED (within U, unmeasured)
inline constexpr std::uint16_t kIrBendTable = 120;       ///< kMaxBends records of 6 registers
inline constexpr std::uint16_t kBendRecordSize = 6;
inline constexpr std::uint16_t kMaxBends = 16;
// A bend record: +0 bend id, +1 flags (BendFlag), +2..3 springback in millidegrees (int32,
// nominal minus measured: positive when the bend opened up), +4..5 measured angle, millideg.
inline constexpr std::uint16_t kBendId = 0;
inline constexpr std::uint16_t kBendFlags = 1;
inline constexpr std::uint16_t kBendSpringback = 2;
inline constexpr std::uint16_t kBendMeasuredAngle = 4;
// The bend shape table (map version 3), record j for bend record j: +0..1 the spread of the
// bend angle along the bend line (max - min over its stations), +2..3 the measured inner radius
// of the bend zone, um; kInvalidInt32 where the report has no such figure.
inline constexpr std::uint16_t kIrBendShapeTable = kIrBendTable + kMaxBends * kBendRecordSize;
inline constexpr std::uint16_t kBendShapeRecordSize = 4;
inline constexpr std::uint16_t kBendAngleSpread = 0;
inline constexpr std::uint16_t kBendMeasuredRadius = 2;
inline constexpr std::uint16_t kResultBlockEnd =
    kIrBendShapeTable + kMaxBends * kBendShapeRecordSize;

// Input registers: the paged window, for PLCs that cannot address past 999.
inline constexpr std::uint16_t kIrWindowPage = 800;  ///< echo of PAGE_SELECT
inline constexpr std::uint16_t kIrWindowSeq = 801;   ///< RESULT_SEQ the window belongs to
inline constexpr std::uint16_t kIrWindowRecords = 802;
inline constexpr std::uint16_t kWindowRecordsPerPage = 15;
inline constexpr std::uint16_t kWindowEnd = kIrWindowRecords + kWindowRecordsPerPage * 8;

// Input registers: the flat compensation-vector block, record i at 1000 + 8 i.
// A record: +0 index i, +1 flags (VectorFlag), +2..3 dx, +4..5 dy, +6..7 dz (int32 um each,
// the compensation vector in the CAD frame). Read in chunks of at most 120 registers.
inline constexpr std::uint16_t kIrVectors = 1000;
inline constexpr std::uint16_t kVectorRecordSize = 8;
inline constexpr std::uint16_t kVectorIndex = 0;
inline constexpr std::uint16_t kVectorFlags = 1;
inline constexpr std::uint16_t kVectorDx = 2;
inline constexpr std::uint16_t kVectorDy = 4;
inline constexpr std::uint16_t kVectorDz = 6;
inline constexpr std::uint16_t kMaxVectors = 1024;
/// PAGE_SELECT 0..kPageCount-1 covers every record of the vector block; a larger value is
/// refused with exception 03 (ILLEGAL DATA VALUE) and the register keeps its old page.
inline constexpr std::uint16_t kPageCount =
    (kMaxVectors + kWindowRecordsPerPage - 1) / kWindowRecordsPerPage;
inline constexpr std::uint16_t kInputRegisterCount = kIrVectors + kMaxVectors * kVectorRecordSize;
/// The chunk a PLC should read at most: a whole number of records, below FC04's limit of 125.
inline constexpr std::uint16_t kRecommendedChunk = 120;

static_assert(kPageCount * kWindowRecordsPerPage >= kMaxVectors, "pages cover the block");
static_assert(kWindowEnd <= kIrVectors, "the window must not overlap the vector block");
static_assert(kResultBlockEnd <= kIrWindowPage, "the result block must end below the window");
static_assert(kInputRegisterCount <= 9999, "five-digit PLC references must reach every value");
static_assert(kHrLiveMirror + kLiveCount <= kHrResultMirror, "live mirror overlaps results");

// ------------------------------------------------------------------------------------------
// Codes.

/// STATE register: PackML-like (ISA-TR88 names; numbers as in the notes, plus sub-states).
enum class State : std::uint16_t {
  kStopped = 0,    ///< starting up
  kIdle = 2,       ///< waiting for a trigger
  kAcquiring = 4,  ///< Execute: the scanner is scanning
  kAnalyzing = 5,  ///< Execute: the scan is being analysed
  kDone = 6,       ///< Complete: a result is in the result block
  kFault = 8,      ///< Aborted: ERROR is set; ERROR_RESET returns to IDLE
};

/// RESULT_CODE register.
enum class ResultCode : std::uint16_t {
  kOk = 0,              ///< part within tolerance (PART_OK = 1)
  kFormNok = 1,         ///< part out of tolerance: see the report's reasons
  kNoData = 2,          ///< no result since start (the block is zero)
  kScanFailed = 3,      ///< the scan did not complete (unplug, timeout, corrupt data)
  kAnalysisFailed = 4,  ///< the scan could not be analysed (too few points, no fit)
  kAmbiguous = 5,       ///< analysed, but two orientations fit within noise: NOK
  /// analysed; nothing is out of tolerance by more than its uncertainty, but something lies
  /// within it of its limit (or a bend was not measured): not OK, re-measure once, then check
  /// by hand (PART_OK = 0, PART_UNDECIDED = 1)
  kUndecided = 6,
};

/// ERROR_CODE register: why ERROR is set. Latched until ERROR_RESET.
enum class ErrorCode : std::uint16_t {
  kNone = 0,
  kScanFailed = 2,          ///< a scan failed (ERROR_DETAIL: ErrorDetail)
  kAnalysisFailed = 3,      ///< the analysis failed
  kPartModelFailed = 4,     ///< the part's CAD model could not be loaded
  kReportWriteFailed = 5,   ///< the report could not be persisted: the result is NOT valid
  kTriggerNotReleased = 6,  ///< TRIGGER stayed high past the release timeout
  kPlcCommLost = 7,         ///< PLC_HEARTBEAT stopped changing
  kInternal = 9,            ///< a bug: see the log
};

/// ERROR_DETAIL register: the cause within ERROR_CODE, where one is known. For ERROR_CODE 2
/// each value is one driver error code (analysis::ErrorCode, daemon plc_error_for_scan).
enum class ErrorDetail : std::uint16_t {
  kNone = 0,
  kDeviceGone = 1,       ///< unplugged during the scan, or not there (kDeviceGone, kNotFound)
  kTimeout = 2,          ///< the device stopped answering (kTimeout)
  kCorruptData = 3,      ///< frames failed their CRC (kBadCrc)
  kCancelled = 4,        ///< the scan was cancelled, e.g. shutdown (kCancelled)
  kStalledEndpoint = 5,  ///< a USB endpoint stalled and could not be cleared (kStalledEndpoint)
  kSequenceGap = 6,      ///< frames or profiles lost or out of order (kSequenceGap)
  kProtocolError = 7,    ///< the device broke the protocol (kProtocolError)
  kDeviceFault = 8,      ///< the device reported an error, e.g. sensor fault (kDeviceFault)
  kOther = 9,            ///< any other cause (kOsError, a config mismatch, ...)
  /// With ERROR_CODE 3 beside a stored NOK result: a datum of the part's alignment could not be
  /// measured (report alignment.failed_datum), the results are in the best-fit frame.
  kDatumNotMeasurable = 10,
};

/// REJECT_CODE register: why the last trigger edge was refused (no Modbus exception is sent).
enum class RejectCode : std::uint16_t {
  kNone = 0,
  kBusy = 1,            ///< an inspection is running
  kNotEnabled = 2,      ///< TRIGGER_ENABLE is 0
  kErrorActive = 3,     ///< ERROR is set: ERROR_RESET first
  kResultNotAcked = 4,  ///< RESULT_VALID is still 1: RESULT_ACK first
  kScannerOffline = 5,  ///< SCANNER_ONLINE is 0
  kUnknownPart = 6,     ///< PART_ID is not in the part catalogue
  kCommLost = 7,        ///< PLC_COMM_LOST is set: PLC_HEARTBEAT, then ERROR_RESET
};

/// Bend record flags.
enum BendFlag : std::uint16_t {
  kBendMeasured = 1u << 0,  ///< both flanges had enough points
  kBendPass = 1u << 1,  ///< |springback| within the angle tolerance (by more than U, guard band)
  kBendNotMeasurable = 1u << 2,  ///< a closed hem: listed, not judged (pass is set)
  kBendUndecided = 1u << 3,      ///< within U of the tolerance, or not measured (map version 6)
};

/// Vector record flags.
enum VectorFlag : std::uint16_t {
  kVectorValid = 1u << 0,    ///< the record holds a vector
  kVectorClipped = 1u << 1,  ///< a component did not fit int32 um and was saturated
};

// ------------------------------------------------------------------------------------------
// Encodings.

/// Word order of 32-bit values. Modbus does not define one (notes section 1).
enum class WordOrder : std::uint8_t {
  kAbcd = 0,  ///< high word at the lower address (default; Gocator, Modicon)
  kCdab = 1,  ///< low word at the lower address (common on Siemens; mbpoll without -B)
};

/// An int32 that says "no value" (the Gocator convention).
inline constexpr std::int32_t kInvalidInt32 = std::numeric_limits<std::int32_t>::min();

/// Writes `value` into words[0..1] in `order`.
constexpr void encode_int32(std::int32_t value, WordOrder order, std::uint16_t* words) {
  const auto u = static_cast<std::uint32_t>(value);
  const auto hi = static_cast<std::uint16_t>(u >> 16);
  const auto lo = static_cast<std::uint16_t>(u & 0xFFFFu);
  words[0] = order == WordOrder::kAbcd ? hi : lo;
  words[1] = order == WordOrder::kAbcd ? lo : hi;
}

/// Reads an int32 from words[0..1] in `order`.
constexpr std::int32_t decode_int32(const std::uint16_t* words, WordOrder order) {
  const std::uint32_t hi = order == WordOrder::kAbcd ? words[0] : words[1];
  const std::uint32_t lo = order == WordOrder::kAbcd ? words[1] : words[0];
  return static_cast<std::int32_t>((hi << 16) | lo);
}

/// Scales a length in mm to int32 um, rounding to nearest; saturates at +-(2^31 - 1) and maps
/// NaN to kInvalidInt32. `clipped` (optional) is set when saturation happened.
inline std::int32_t mm_to_um(double mm, bool* clipped = nullptr) {
  if (mm != mm) return kInvalidInt32;  // NaN
  const double um = mm * 1000.0;
  constexpr double kMax = 2147483647.0;
  const bool clip = um > kMax || um < -kMax;
  if (clipped != nullptr && clip) *clipped = true;
  if (um > kMax) return std::numeric_limits<std::int32_t>::max();
  if (um < -kMax) return -std::numeric_limits<std::int32_t>::max();
  return static_cast<std::int32_t>(um < 0 ? um - 0.5 : um + 0.5);
}

/// Scales an angle in degrees to int32 millidegrees (same rounding and saturation).
inline std::int32_t deg_to_mdeg(double deg) { return mm_to_um(deg); }

/// Result sequence number k of the station's lifetime (k >= 1) as the 16-bit RESULT_SEQ:
/// 1..65535, wrapping to 1, never 0 (0 means "no result").
constexpr std::uint16_t result_seq_from_record(std::uint64_t k) {
  return static_cast<std::uint16_t>((k - 1) % 65535u + 1u);
}

}  // namespace springscan::daemon::regs
