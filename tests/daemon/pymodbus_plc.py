#!/usr/bin/python3
"""A third-party PLC client for springscand, written from docs/modbus-register-map.md alone.

Debian's python3-pymodbus (3.0; the 2.x API differs: unit= instead of slave=). Drives the whole
handshake: trigger, TRIG_ACK, drop TRIGGER, RESULT_VALID, the result block, the bend records,
every compensation vector (flat block and paged window, which must agree), the FC03 mirror,
RESULT_ACK and PLC_HEARTBEAT; then a PLC outage with a result pending (PLC_COMM_LOST, ERROR_CODE
7, ERROR_RESET keeps the result) and PAGE_SELECT past the last page (exception 03).

  pymodbus_plc.py --port PORT [--cycles N] [--job FIRST_JOB] [--part PART_ID]

Prints one line per collected result ("RESULT seq=... n=... max_dev_um=...") and exits 0 when
every check held, 1 with the failed check otherwise. Unit id: pymodbus's default 0, which the
station answers like 255 (doc, "Unit id").
"""

import argparse
import sys
import time

from pymodbus.client import ModbusTcpClient

# Coils (doc "Coils").
TRIGGER_ENABLE, TRIGGER, RESULT_ACK, ERROR_RESET = 0, 1, 2, 3
# Discrete inputs (doc "Discrete inputs").
READY, TRIG_ACK, BUSY, RESULT_VALID, PART_OK, ERROR, TRIGGER_REJECTED = 0, 1, 2, 3, 4, 5, 6
SCANNER_ONLINE, HEARTBEAT_BIT, PLC_COMM_LOST, RESULT_STALE = 7, 8, 9, 10
CALIBRATION_DRIFT, PART_UNDECIDED = 11, 12
RESULT_CODE_UNDECIDED = 6
# Holding registers.
CONTROL_WORD, JOB_ID, PART_ID, PLC_HEARTBEAT, PAGE_SELECT, PART_SERIAL = 0, 1, 2, 3, 4, 5
SERIAL_BASE = 70000  # PART_SERIAL = SERIAL_BASE + JOB_ID: above 16 bits, so both words count
# Input registers.
MAP_VERSION, BOOT_ID, STATE, HEARTBEAT, ERROR_CODE = 0, 1, 2, 3, 4
ENDIAN_PROBE, STATUS_WORD, REJECT_CODE = 7, 9, 10
RESULT_BLOCK, RESULT_BLOCK_COUNT = 100, 116  # 100..215: the block and 16 bend records
WINDOW, WINDOW_COUNT = 800, 122  # 800 page echo, 801 seq, 802..921 15 records
VECTORS, RECORD, CHUNK, PAGE_RECORDS, PAGES = 1000, 8, 120, 15, 69
NO_VALUE = -2147483648
STATE_DONE = 6
ERROR_PLC_COMM_LOST = 7


class CheckFailed(Exception):
    pass


def check(condition, what):
    if not condition:
        raise CheckFailed(what)


def int32(words, at):
    """ABCD (the default word order): high word at the lower address."""
    value = (words[at] << 16) | words[at + 1]
    return value - (1 << 32) if value & 0x80000000 else value


class Plc:
    def __init__(self, port, step_timeout_s):
        self.client = ModbusTcpClient("127.0.0.1", port=port, timeout=10)
        check(self.client.connect(), "connect to 127.0.0.1:%d" % port)
        self.timeout_s = step_timeout_s
        self.heartbeat = 0

    # One request each; every reply must be a normal one.
    def input_registers(self, address, count):
        reply = self.client.read_input_registers(address, count)
        check(not reply.isError(), "FC04 %d+%d: %s" % (address, count, reply))
        return reply.registers[:count]

    def holding_registers(self, address, count):
        reply = self.client.read_holding_registers(address, count)
        check(not reply.isError(), "FC03 %d+%d: %s" % (address, count, reply))
        return reply.registers[:count]

    def inputs(self):
        reply = self.client.read_discrete_inputs(0, 13)
        check(not reply.isError(), "FC02: %s" % reply)
        return reply.bits[:13]

    def coil(self, address, value):
        reply = self.client.write_coil(address, value)
        check(not reply.isError(), "FC05 %d: %s" % (address, reply))

    def registers(self, address, values):
        reply = self.client.write_registers(address, values)
        check(not reply.isError(), "FC16 %d: %s" % (address, reply))

    def beat(self):
        """PLC_HEARTBEAT: a new value at least once a second (doc "Handshake")."""
        self.heartbeat = (self.heartbeat + 1) & 0xFFFF
        reply = self.client.write_register(PLC_HEARTBEAT, self.heartbeat)
        check(not reply.isError(), "FC06 PLC_HEARTBEAT: %s" % reply)

    def wait(self, bit, value, what, beat=True):
        deadline = time.monotonic() + self.timeout_s
        while time.monotonic() < deadline:
            if beat:
                self.beat()
            bits = self.inputs()
            if bits[bit] == value:
                return bits
            time.sleep(0.02)  # a PLC's scan cycle
        raise CheckFailed("timed out waiting for " + what)

    def pulse(self, coil, until_bit, until_value, what):
        self.coil(coil, True)
        self.wait(until_bit, until_value, what)
        self.coil(coil, False)


def check_live_block(plc):
    live = plc.input_registers(0, 13)
    check(live[MAP_VERSION] == 6, "MAP_VERSION %d, this client is written for 6" % live[0])
    check(live[BOOT_ID] != 0, "BOOT_ID is never 0")
    check(live[ENDIAN_PROBE:ENDIAN_PROBE + 2] == [0x0102, 0x0304], "endianness probe (ABCD)")
    mirror = plc.holding_registers(10, 13)  # FC03 copy of input registers 0-12
    check(mirror[MAP_VERSION] == 6 and mirror[BOOT_ID] == live[BOOT_ID], "live mirror at 10")
    return live


def trigger(plc, job, part, serial):
    """Handshake steps 1-3: READY, PART_SERIAL, one FC16 write of CONTROL_WORD/JOB_ID/PART_ID,
    TRIG_ACK."""
    plc.wait(READY, True, "READY = 1")
    plc.registers(PART_SERIAL, [serial >> 16, serial & 0xFFFF])  # 32-bit, word order ABCD
    plc.registers(CONTROL_WORD, [0b011, job, part])  # TRIGGER_ENABLE + TRIGGER, the ids
    deadline = time.monotonic() + plc.timeout_s
    while True:
        bits = plc.inputs()
        if bits[TRIG_ACK]:
            break
        if bits[TRIGGER_REJECTED]:
            code = plc.input_registers(REJECT_CODE, 1)[0]
            raise CheckFailed("trigger refused, REJECT_CODE %d" % code)
        check(time.monotonic() < deadline, "TRIG_ACK = 1")
        time.sleep(0.005)
    plc.registers(CONTROL_WORD, [0b001])  # drop TRIGGER through CONTROL_WORD, keep enable
    plc.wait(TRIG_ACK, False, "TRIG_ACK = 0 after TRIGGER dropped")


def read_flat_vectors(plc, n):
    words = []
    end = VECTORS + RECORD * n
    for address in range(VECTORS, end, CHUNK):
        words += plc.input_registers(address, min(CHUNK, end - address))
    if n < 1024:  # the record past N is zero
        check(plc.input_registers(end, RECORD) == [0] * RECORD, "record N is empty")
    return words


def read_paged_vectors(plc, n, seq):
    words = []
    pages = (n + PAGE_RECORDS - 1) // PAGE_RECORDS
    for page in range(pages):
        plc.registers(PAGE_SELECT, [page])
        window = plc.input_registers(WINDOW, WINDOW_COUNT)
        check(window[0] == page, "window echo %d for page %d" % (window[0], page))
        check(window[1] == seq, "window RESULT_SEQ %d, result %d" % (window[1], seq))
        words += window[2:]
    return words[:RECORD * n]


def read_result(plc):
    """Handshake step 5: RESULT_SEQ, the block, the vectors, RESULT_SEQ again."""
    for _attempt in range(3):
        block = plc.input_registers(RESULT_BLOCK, RESULT_BLOCK_COUNT)
        seq, n, bend_count = block[0], block[8], block[12]
        check(seq != 0, "RESULT_SEQ is never 0 once a result exists")
        check(block[9] == RECORD and block[13] == 6, "record sizes 8 and 6")
        check(n <= 1024 and bend_count <= 16, "N %d, BEND_COUNT %d" % (n, bend_count))
        check(block[19] == 0, "register 119 is reserved, 0")
        flat = read_flat_vectors(plc, n)
        paged = read_paged_vectors(plc, n, seq)
        mirror = plc.holding_registers(RESULT_BLOCK, RESULT_BLOCK_COUNT)
        if plc.input_registers(RESULT_BLOCK, 1)[0] == seq:
            break
    else:
        raise CheckFailed("RESULT_SEQ kept changing")
    check(mirror == block, "FC03 mirror of the result block")
    check(paged == flat, "the paged window matches the flat block")
    for i in range(n):
        record = flat[RECORD * i:RECORD * (i + 1)]
        check(record[0] == i and record[1] & 1, "vector record %d: index and valid flag" % i)
    bends = []
    for j in range(bend_count):
        record = block[20 + 6 * j:26 + 6 * j]
        bends.append({"id": record[0], "flags": record[1], "springback_mdeg": int32(record, 2),
                      "angle_mdeg": int32(record, 4)})
    code = block[3]
    result = {"seq": seq, "part": block[1], "job": block[2], "code": code,
              "max_dev_um": int32(block, 4), "rms_dev_um": int32(block, 6), "n": n,
              "cycle_ms": int32(block, 10), "bends": bends, "bends_failed": block[14],
              "p95_dev_um": int32(block, 15), "points": int32(block, 17)}
    if code in (0, 1):
        check(result["max_dev_um"] >= 0, "MAX_DEV is a magnitude")
        check(result["p95_dev_um"] <= result["max_dev_um"], "P95_DEV <= MAX_DEV")
    return result


def acknowledge(plc, result):
    bits = plc.inputs()
    check(bits[RESULT_VALID], "RESULT_VALID still 1 before RESULT_ACK")
    check(bits[PART_OK] == (result["code"] == 0), "PART_OK agrees with RESULT_CODE")
    check(bits[PART_UNDECIDED] == (result["code"] == RESULT_CODE_UNDECIDED),
          "PART_UNDECIDED agrees with RESULT_CODE")
    check(not (bits[PART_OK] and bits[PART_UNDECIDED]), "never PART_OK and PART_UNDECIDED")
    plc.pulse(RESULT_ACK, RESULT_VALID, False, "RESULT_VALID = 0 after RESULT_ACK")


def print_result(r):
    print("RESULT seq=%d job=%d part=%d code=%d n=%d bends=%d max_dev_um=%d p95_dev_um=%d "
          "springback_mdeg=%s" % (r["seq"], r["job"], r["part"], r["code"], r["n"],
                                  len(r["bends"]), r["max_dev_um"], r["p95_dev_um"],
                                  ",".join(str(b["springback_mdeg"]) for b in r["bends"])))
    sys.stdout.flush()


def outage_with_a_result_pending(plc, job, part):
    """The PLC stops its heartbeat with a result unread, comes back, resets, then collects it."""
    trigger(plc, job, part, SERIAL_BASE + job)
    plc.wait(RESULT_VALID, True, "RESULT_VALID = 1")
    time.sleep(4.0)  # no PLC_HEARTBEAT for longer than plc_heartbeat_timeout_s (3 s)
    bits = plc.inputs()
    check(bits[PLC_COMM_LOST] and bits[ERROR] and not bits[READY], "PLC_COMM_LOST, ERROR")
    check(plc.input_registers(ERROR_CODE, 1)[0] == ERROR_PLC_COMM_LOST, "ERROR_CODE 7")
    check(bits[RESULT_VALID], "the outage keeps RESULT_VALID")
    plc.beat()
    plc.pulse(ERROR_RESET, ERROR, False, "ERROR = 0 after ERROR_RESET")
    bits = plc.inputs()
    check(not bits[PLC_COMM_LOST] and bits[RESULT_VALID], "ERROR_RESET kept the result")
    check(plc.input_registers(STATE, 1)[0] == STATE_DONE, "STATE DONE with a result shown")
    result = read_result(plc)
    check(result["job"] == job, "the pending result is job %d" % job)
    acknowledge(plc, result)
    return result


def page_select_past_the_last_page_is_refused(plc):
    reply = plc.client.write_register(PAGE_SELECT, PAGES)
    check(reply.isError() and getattr(reply, "exception_code", 0) == 3,
          "PAGE_SELECT %d answered exception 03: %s" % (PAGES, reply))
    plc.registers(PAGE_SELECT, [PAGES - 1])
    check(plc.input_registers(WINDOW, 1)[0] == PAGES - 1, "page %d is accepted" % (PAGES - 1))


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--port", type=int, required=True)
    parser.add_argument("--cycles", type=int, default=2)
    parser.add_argument("--job", type=int, default=100)
    parser.add_argument("--part", type=int, default=1)
    parser.add_argument("--step-timeout-s", type=float, default=180.0)
    args = parser.parse_args()
    plc = Plc(args.port, args.step_timeout_s)
    try:
        live = check_live_block(plc)
        plc.beat()
        plc.coil(TRIGGER_ENABLE, True)
        plc.wait(SCANNER_ONLINE, True, "SCANNER_ONLINE = 1")
        seen = []
        for k in range(args.cycles):
            job = args.job + k
            trigger(plc, job, args.part, SERIAL_BASE + job)
            plc.wait(RESULT_VALID, True, "RESULT_VALID = 1")
            result = read_result(plc)
            check(result["job"] == job and result["part"] == args.part, "ids echoed")
            acknowledge(plc, result)
            print_result(result)
            seen.append(result["seq"])
        print_result(outage_with_a_result_pending(plc, args.job + args.cycles, args.part))
        page_select_past_the_last_page_is_refused(plc)
        check(plc.input_registers(BOOT_ID, 1)[0] == live[BOOT_ID], "no restart meanwhile")
        check(len(set(seen)) == len(seen), "every RESULT_SEQ new")
    except CheckFailed as failed:
        print("FAILED: " + str(failed))
        return 1
    finally:
        plc.client.close()
    print("OK")
    return 0


if __name__ == "__main__":
    sys.exit(main())
