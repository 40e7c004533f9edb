#!/usr/bin/python3
"""Independent checker of what vcu-can-tx put on a real CAN interface (tests/kernel).

Reads a `candump -L` log and checks, from the DBC and the schedule file alone (no project
code is used):
  * periods: every periodic message this node transmits (DBC GenMsgCycleTime, or the
    schedule's cycleMs) whose cycle fits at least 4 times in the log: no gap >= 2 cycles,
    mean period within --mean-tolerance (default 5 %) of the cycle;
  * J1939-76 safety pairs (schedule "safety"): each SDM comes after an unused SHM of the
    SHM identifier, SHM -> SDM delay between 0.8 x deltaUs and half the SDM's cycle (the
    emulated kernel of tests/kernel cannot hold sub-millisecond deltas; the measured range
    is printed), or deltaUs + --max-extra-delay-ms when that is given,
    SHM byte 0 = sequence << 3 | 1 << 2 | ~EDP << 1 | ~DP, bytes 1-3 = ~SA ~PS ~PF of the SDM,
    bytes 4-7 = CRC-32 (poly 0x6938392D, init 0xFFFFFFFF, not reflected, no final XOR) of the
    SDM's 8 bytes, least significant byte first, and sequence = previous + 1 mod 32.
Facts from shared/j1939/include/openvcu/j1939/safety.hpp and docs/design/can-tx.md.

  check_tx.py [--part periods|j1939_76] --dbc F.dbc --schedule S.json --node NAME LOG
                                                              exit 0 pass, 1 fail
  check_tx.py --self-test                                     checks the checker
"""
import argparse
import json
import re
import sys

CRC_POLY, CRC_INIT = 0x6938392D, 0xFFFFFFFF
SHM_PGN = 0x0E00


def crc32_j1939_76(data):
    reg = CRC_INIT
    for byte in data:
        reg ^= byte << 24
        for _ in range(8):
            reg = ((reg << 1) ^ CRC_POLY) if reg & 0x80000000 else (reg << 1)
            reg &= 0xFFFFFFFF
    return reg


def shm_id(sdm_id):
    """The SHM's 29-bit ID: PGN 0x0E00 (PDU1, DP 0) from the SDM's SA to its DA, its priority."""
    prio, pf, ps, sa = (sdm_id >> 26) & 7, (sdm_id >> 16) & 0xFF, (sdm_id >> 8) & 0xFF, sdm_id & 0xFF
    da = ps if pf < 240 else 0xFF
    return (prio << 26) | (SHM_PGN << 8) | (da << 8) | sa


def expected_shm_fields(sdm_id, data):
    edp, dp = (sdm_id >> 25) & 1, (sdm_id >> 24) & 1
    pf, ps, sa = (sdm_id >> 16) & 0xFF, (sdm_id >> 8) & 0xFF, sdm_id & 0xFF
    crc = crc32_j1939_76(data)
    rest = bytes([sa ^ 0xFF, ps ^ 0xFF, pf ^ 0xFF, crc & 0xFF, (crc >> 8) & 0xFF, (crc >> 16) & 0xFF, crc >> 24])
    low_bits = 0x04 | ((edp ^ 1) << 1) | (dp ^ 1)
    return low_bits, rest


def read_log(path):
    """candump -L lines -> [(time_s, can_id, data bytes)]; classic and FD frames, no remote frames."""
    frames, drops = [], []
    pattern = re.compile(r"^\((\d+\.\d+)\)\s+\S+\s+([0-9A-Fa-f]+)(##?)([0-9A-Fa-fR]*)\s*$")
    with open(path) as log:
        for line in log:
            if "DROPCOUNT" in line:  # candump -d: the recorder itself lost frames
                drops.append(line.strip())
            match = pattern.match(line.strip())
            if not match or "R" in match.group(4):
                continue
            stamp, ident, sep, payload = match.groups()
            if sep == "##":
                payload = payload[1:]  # FD: the first nibble is the flags
            frames.append((float(stamp), int(ident, 16), bytes.fromhex(payload)))
    return frames, drops


def read_expectations(dbc_path, schedule_path, node):
    """{can_id: (name, cycle_ms or None, sdm delta_us or None)} for the node's transmitted messages."""
    text = open(dbc_path, encoding="utf-8", errors="replace").read()
    messages = {}
    for dbc_id, name, sender in re.findall(r"^BO_\s+(\d+)\s+(\w+)\s*:\s*\d+\s+(\w+)", text, re.M):
        if sender == node:
            messages[name] = int(dbc_id) & 0x1FFFFFFF
    cycles = {int(i) & 0x1FFFFFFF: int(ms) for i, ms in
              re.findall(r'^BA_\s+"GenMsgCycleTime"\s+BO_\s+(\d+)\s+(\d+)\s*;', text, re.M)}
    schedule = json.load(open(schedule_path))
    sched_msgs = schedule.get("messages", {})
    result = {}
    for name, can_id in messages.items():
        entry = sched_msgs.get(name, {})
        if (can_id >> 16) & 0x3FF == SHM_PGN >> 8:
            continue  # the SHM messages (PGN 0x0E00) go out with their SDM, checked as pairs
        cycle = entry.get("cycleMs", cycles.get(can_id))
        if entry.get("onChange"):
            cycle = None  # extra frames on change: the period check does not apply
        delta = entry.get("safety", {}).get("deltaUs") if entry.get("safety") else None
        result[can_id] = (name, cycle, delta)
    return result


def check(frames, expectations, mean_tol, max_extra_delay_ms, part="all", max_gap_cycles=2.0):
    cycles = {can_id: cycle for can_id, (_, cycle, _) in expectations.items()}
    failures, notes = [], []
    if not frames:
        return ["the log holds no frames"], notes
    if part == "j1939_76":  # pairing, content and sequence only; timing is the periods part
        expectations = {k: (n, None, d) for k, (n, _, d) in expectations.items()}
    duration = frames[-1][0] - frames[0][0]
    by_id = {}
    for stamp, can_id, data in frames:
        by_id.setdefault(can_id, []).append((stamp, data))
    checked = 0
    for can_id, (name, cycle, _) in sorted(expectations.items()):
        if not cycle or cycle / 1000.0 * 4 > duration:
            continue
        stamps = [s for s, _ in by_id.get(can_id, [])]
        if len(stamps) < 3:
            failures.append("%s (0x%08X): %d frames in %.2f s, cycle %d ms" % (name, can_id, len(stamps), duration, cycle))
            continue
        gaps = [b - a for a, b in zip(stamps, stamps[1:])]
        mean_ms = (stamps[-1] - stamps[0]) / (len(stamps) - 1) * 1000.0
        max_ms = max(gaps) * 1000.0
        line = "%s 0x%08X cycle %d ms: %d frames, mean %.3f ms, max gap %.3f ms" % (
            name, can_id, cycle, len(stamps), mean_ms, max_ms)
        checked += 1
        if max_ms >= max_gap_cycles * cycle:
            failures.append(line + " (gap >= %g cycles)" % max_gap_cycles)
        elif abs(mean_ms - cycle) > mean_tol * cycle:
            failures.append(line + " (mean off by more than %.0f %%)" % (mean_tol * 100))
        else:
            notes.append(line)
    if checked == 0 and part != "j1939_76":
        failures.append("no periodic message could be checked (log %.2f s)" % duration)

    # J1939-76 pairs, walking the log in order. Several SDMs can share one SHM identifier
    # (every PDU2 SDM of a source goes with SHM PGN 0x0E00 to global), so an SHM belongs to
    # the SDM whose inverted EDP/DP/SA/PS/PF it carries.
    sdms = {can_id: (name, delta) for can_id, (name, _, delta) in expectations.items() if delta}
    header_ids = {shm_id(sdm) for sdm in sdms}
    state = {sdm: {"pending": None, "last_seq": None, "pairs": 0, "errors": [], "late": [], "delays": []}
             for sdm in sdms}
    stray = []
    for stamp, can_id, data in frames:
        if can_id in header_ids:
            target = None
            for sdm in sdms:
                if shm_id(sdm) == can_id and len(data) == 8 and data[0] & 0x07 == expected_shm_fields(sdm, bytes(8))[0] \
                        and data[1:4] == expected_shm_fields(sdm, bytes(8))[1][:3]:
                    target = sdm
            if target is None:
                stray.append("SHM %s at %.6f names no scheduled SDM" % (data.hex(), stamp))
                continue
            st = state[target]
            if st["pending"] is not None:
                st["errors"].append("SHM at %.6f without its SDM" % st["pending"][0])
            st["pending"] = (stamp, data)
        elif can_id in sdms:
            st, delta_us = state[can_id], sdms[can_id][1]
            if st["pending"] is None:
                if st["pairs"] or st["errors"]:  # the log may start between an SHM and its SDM
                    st["errors"].append("SDM at %.6f without an SHM before it" % stamp)
                continue
            shm_stamp, shm = st["pending"]
            st["pending"] = None
            delay_us = (stamp - shm_stamp) * 1e6
            st["delays"].append(delay_us)
            if len(data) != 8:
                st["errors"].append("SDM length %d at %.6f" % (len(data), stamp))
                continue
            low_bits, rest = expected_shm_fields(can_id, data)
            seq = shm[0] >> 3
            if shm[0] & 0x07 != low_bits or shm[1:] != rest:
                st["errors"].append("SHM %s does not match SDM %s at %.6f (CRC expected %s)" % (
                    shm.hex(), data.hex(), stamp, rest[3:].hex()))
            if st["last_seq"] is not None and seq != (st["last_seq"] + 1) % 32:
                st["errors"].append("sequence %d after %d at %.6f" % (seq, st["last_seq"], stamp))
            if max_extra_delay_ms is not None:
                longest_us = delta_us + max_extra_delay_ms * 1000
            else:
                longest_us = (cycles.get(can_id) or 0) * 500.0 or delta_us + 5000
            if not (0.8 * delta_us <= delay_us <= longest_us):
                st["late"].append("SHM->SDM %.0f us at %.6f (delta %d us)" % (delay_us, stamp, delta_us))
            st["last_seq"] = seq
            st["pairs"] += 1
    if stray and part != "periods":
        failures.append("; ".join(stray[:3]))
    for sdm, (name, delta_us) in sorted(sdms.items()):
        st = state[sdm]
        summary = "J1939-76 %s 0x%08X / SHM 0x%08X: %d pairs" % (name, sdm, shm_id(sdm), st["pairs"])
        if st["delays"]:
            summary += ", SHM->SDM %.0f..%.0f us (delta %d us)" % (min(st["delays"]), max(st["delays"]), delta_us)
        # periods: the SHM -> SDM delay; j1939_76: pairing, bytes, CRC, sequence; all: both
        errors = {"periods": st["late"], "j1939_76": st["errors"]}.get(part, st["errors"] + st["late"])
        if part == "periods" and not errors:
            notes.append(summary)
            continue
        if errors:
            failures.append(summary + ": " + "; ".join(errors[:4]) +
                            (" (+%d more)" % (len(errors) - 4) if len(errors) > 4 else ""))
        elif st["pairs"] < 2:
            failures.append(summary + " (fewer than 2 pairs)")
        else:
            notes.append(summary)
    return failures, notes


def self_test():
    """The checker must reject what is wrong: a known answer and broken logs."""
    assert crc32_j1939_76(bytes.fromhex("EFFFFFFFFFFFFFFF")) == 0x8100EFA3
    assert shm_id(0x0CEFF321) == 0x0C0EF321 and shm_id(0x18FEF121) == 0x180EFF21
    sdm, data = 0x0CEFF321, bytes.fromhex("EFFFFFFFFFFFFFFF")
    low, rest = expected_shm_fields(sdm, data)
    assert bytes([15 << 3 | low]) + rest == bytes.fromhex("7FDE0C10A3EF0081")  # thesis Fig. 6.11/6.13
    exp = {sdm: ("S1", 20, 292), 0x18FEF521: ("AMB", 100, None), 0x18FEF121: ("CCVS1", 100, 2000),
           0x18F02B21: ("CN", 100, 1427)}  # CCVS1 and CN share SHM 0x180EFF21

    def log(corrupt=None):
        frames, seq = [], 0
        for k in range(50):
            t = k * 0.020
            low, rest = expected_shm_fields(sdm, data)
            shm = bytes([seq << 3 | low]) + rest
            if corrupt == "crc" and k == 20:
                shm = shm[:7] + bytes([shm[7] ^ 1])
            if corrupt == "seq" and k == 30:
                seq = (seq + 1) % 32
            delay = {"late": 0.015, "early": 0.0001}.get(corrupt, 0.0003) if k == 25 else 0.0003
            if not (corrupt == "gap" and k in (10, 11)):
                frames.append((t, shm_id(sdm), shm))
                if not (corrupt == "lost_sdm" and k == 15):
                    frames.append((t + delay, sdm, data))
            if k % 5 == 0:
                frames.append((t + 0.001, 0x18FEF521, bytes(8)))
                for other, delay, value in ((0x18FEF121, 0.002, b"\x01" * 8), (0x18F02B21, 0.0015, b"\x02" * 8)):
                    low, rest = expected_shm_fields(other, value)
                    frames.append((t + 0.0002, shm_id(other), bytes([(k // 5 % 32) << 3 | low]) + rest))
                    frames.append((t + 0.0002 + delay, other, value))
            seq = (seq + 1) % 32
        frames.sort(key=lambda frame: frame[0])
        return frames

    assert check(log(), exp, 0.05, None)[0] == [], check(log(), exp, 0.05, None)
    for corrupt in ("crc", "seq", "gap", "lost_sdm", "late", "early"):
        failures = check(log(corrupt), exp, 0.05, None)[0]
        assert failures, "the checker accepted a log with a %s fault" % corrupt
        print("self-test: %s fault rejected: %s" % (corrupt, failures[0][:110]))
    print("self-test: PASS")
    return 0


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("log", nargs="?")
    parser.add_argument("--dbc")
    parser.add_argument("--schedule")
    parser.add_argument("--node")
    parser.add_argument("--mean-tolerance", type=float, default=0.05)
    parser.add_argument("--max-gap-cycles", type=float, default=2.0,
                        help="a gap of this many cycles or more fails (default 2: no missed cycle)")
    parser.add_argument("--max-extra-delay-ms", type=float, default=None)
    parser.add_argument("--part", choices=("all", "periods", "j1939_76"), default="all")
    parser.add_argument("--self-test", action="store_true")
    args = parser.parse_args()
    if args.self_test:
        return self_test()
    if not (args.log and args.dbc and args.schedule and args.node):
        parser.error("LOG, --dbc, --schedule and --node are required")
    frames, drops = read_log(args.log)
    expectations = read_expectations(args.dbc, args.schedule, args.node)
    failures, notes = check(frames, expectations, args.mean_tolerance, args.max_extra_delay_ms, args.part,
                            args.max_gap_cycles)
    if drops:  # gaps and lost SDMs may be the recorder's, not the sender's: never a pass
        failures.insert(0, "the recording lost frames (candump -d): " + "; ".join(drops[:3]))
    print("check_tx: %d frames, %.2f s" % (len(frames), frames[-1][0] - frames[0][0] if frames else 0))
    for note in notes:
        print("  ok   " + note)
    for failure in failures:
        print("  FAIL " + failure)
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
