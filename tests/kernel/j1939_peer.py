#!/usr/bin/env python3
"""Another J1939 node on vcan0, made of the kernel's can-j1939 sockets (no project code):
the VM test's independent view of the VCU as a J1939 network citizen (issue 24).

  j1939_peer.py diag --diagnostics FILE --state NAME --signal KEY [--to ADDR] [--version V]
    j1939_dm1_bam: receive the VCU's DM1 (PGN 0xFECA) as the kernel delivers it (a BAM the
      kernel reassembled when longer than 8 bytes) with the DTCs diagnostics.json maps to the
      FSM state NAME and to the signal KEY (SPN and FMI read from the file, not hard-coded)
    j1939_rts_cts_to_kernel: a socket at 0xF9 requests (PGN 0xEA00) ECU Identification 64965
      from ADDR (default 0x21): the answer comes by RTS/CTS to 0xF9 (the kernel sends CTS and
      EndOfMsgAck) and must equal the '*'-terminated fields of diagnostics.json
    j1939_bam_to_kernel: the same for Software Identification 65242 requested from all
      (0xFF): by BAM; the field count, the configured fields and "openvcu VERSION" (the field
      the service appends; VERSION as given, else any text without '*')
  j1939_peer.py contest --vcu-name M [--address A]
    j1939_address_defend: a kernel socket with NAME M+1 (lower priority) claims A (default
      0x21; the kernel sends the Address Claimed when the socket sends PGN 0xEE00 with its
      NAME): the VCU (NAME M, a fixed address) must claim A again and no other address
    j1939_address_lost: a kernel socket with NAME M-1 (higher priority) claims A: the VCU
      must send Cannot Claim (its NAME from 0xFE) within 1 s, claim no other address, and
      then send nothing from A and no J1939-76 SHM (PF 0x0E) from any address for 1 s; the
      same claim three times more: no claim from the VCU at all (it does not wander)

Prints one line "CHECK PASS|FAIL detail" per check, exit 0 when all passed.
"""
import argparse
import json
import socket
import struct
import sys
import time

IF = "vcan0"
PGN_DM1 = 0xFECA          # 65226 DM1 active diagnostic trouble codes (J1939-73)
PGN_REQUEST = 0xEA00      # 59904 Request (J1939-21)
PGN_CLAIM = 0xEE00        # 60928 Address Claimed (J1939-81)
PGN_SOFT = 0xFEDA         # 65242 Software Identification
PGN_ECUID = 0xFDC5        # 64965 ECU Identification
# linux/can/j1939.h; Python's socket module may lack them
SOL_CAN_J1939 = getattr(socket, "SOL_CAN_J1939", 100 + socket.CAN_J1939)   # SOL_CAN_BASE + CAN_J1939
SO_J1939_PROMISC = getattr(socket, "SO_J1939_PROMISC", 2)
PEER = 0xF9               # our address for the requests (a service tool's)


def j1939_socket(name=socket.J1939_NO_NAME, pgn=socket.J1939_NO_PGN, addr=socket.J1939_NO_ADDR,
                 promisc=False):
    s = socket.socket(socket.AF_CAN, socket.SOCK_DGRAM, socket.CAN_J1939)
    s.setsockopt(socket.SOL_SOCKET, socket.SO_BROADCAST, 1)
    if promisc:
        s.setsockopt(SOL_CAN_J1939, SO_J1939_PROMISC, 1)
    s.bind((IF, name, pgn, addr))
    return s


def report(check, ok, text):
    print("%s %s %s" % (check, "PASS" if ok else "FAIL", text), flush=True)
    return ok


def dtcs_of(payload):
    """(spn, fmi, oc) of each 4-byte DTC after the two lamp bytes (J1939-73 conversion method 4)"""
    out = []
    for i in range(2, len(payload) - 3, 4):
        d = payload[i:i + 4]
        spn = d[0] | d[1] << 8 | (d[2] >> 5) << 16
        if spn or d[2] & 0x1F:
            out.append((spn, d[2] & 0x1F, d[3] & 0x7F))
    return out


def cmd_dm1(args):
    dtcs = json.load(open(args.diagnostics))["dtcs"]
    want = [(d["spn"], d["fmi"]) for d in dtcs
            if d.get("fsmState") == args.state or d.get("signal") == args.signal]
    if len(want) < 2:
        return False, ("diagnostics.json maps %s / %s to %d DTCs, want 2" % (args.state, args.signal, len(want)))
    s = j1939_socket(pgn=PGN_DM1)
    s.settimeout(0.5)
    end, seen = time.time() + args.timeout, []
    while time.time() < end:
        try:
            data, (_, _, pgn, sa) = s.recvfrom(1785)
        except socket.timeout:
            continue
        got = dtcs_of(data)
        seen.append("SA %02X %d bytes %s" % (sa, len(data), data.hex()))
        if sa == args.source and all(any(g[:2] == w for g in got) for w in want):
            return len(data) > 8, ("kernel delivered DM1 from SA %02X, %d bytes (%s), DTCs %s contain %s"
                   % (sa, len(data), "BAM reassembled" if len(data) > 8 else "single frame: no BAM", got, want))
    return False, ("no DM1 with %s within %.0f s; seen: %s" % (want, args.timeout, " | ".join(seen[-4:]) or "none"))


def cmd_request(args):
    ident = json.load(open(args.diagnostics))["identification"]
    if args.pgn == PGN_ECUID:
        e = ident["ecu"]
        fields = [e.get(k, "") for k in ("partNumber", "serialNumber", "location", "type", "manufacturer", "hardwareId")]
        want = "".join(f + "*" for f in fields).encode()
    elif args.pgn == PGN_SOFT:
        # the configured fields, then the one the service appends: "openvcu " + its build
        # version (given with --version, else taken from the answer after checking its form)
        fields = list(ident["software"])
        want = bytes([len(fields) + 1]) + "".join(f + "*" for f in fields).encode() + b"openvcu "
    else:
        return False, "unsupported PGN %d" % pgn
    s = j1939_socket(pgn=args.pgn, addr=PEER)
    s.settimeout(args.timeout)
    s.sendto(bytes([args.pgn & 0xFF, args.pgn >> 8 & 0xFF, args.pgn >> 16 & 0xFF]),
             (IF, socket.J1939_NO_NAME, PGN_REQUEST, args.to))
    end = time.time() + args.timeout
    while time.time() < end:
        try:
            data, (_, _, pgn, sa) = s.recvfrom(1785)
        except socket.timeout:
            break
        if pgn != args.pgn:
            continue
        if args.pgn == PGN_SOFT:
            tail = data[len(want):]
            version = args.version.encode() if args.version else tail[:-1]
            if data.startswith(want) and tail.endswith(b"*") and version and b"*" not in version:
                want += version + b"*"
        how = "BAM" if args.to == 0xFF else "RTS/CTS to %02X" % PEER
        return data == want and len(data) > 8, (
               "request PGN %d to %02X -> kernel delivered %d bytes from SA %02X (%s): %r%s"
               % (args.pgn, args.to, len(data), sa, how, data, "" if data == want else " != expected %r" % want))
    return False, ("no answer for PGN %d from %02X within %.0f s (want %r)" % (args.pgn, args.to, args.timeout, want))


def cmd_claim(args):
    vcu_name = args.vcu_name.to_bytes(8, "little")
    watch = j1939_socket(pgn=PGN_CLAIM, promisc=True)
    watch.settimeout(0.2)
    peer = j1939_socket(name=args.name, addr=args.address)
    peer.sendto(args.name.to_bytes(8, "little"), (IF, socket.J1939_NO_NAME, PGN_CLAIM, 0xFF))
    sent = time.time()
    vcu_claims = []   # (seconds after ours, address) of the VCU's Address Claimed
    while time.time() < sent + args.timeout:
        try:
            data, (_, _, _, sa) = watch.recvfrom(8)
        except socket.timeout:
            continue
        if data == vcu_name:
            vcu_claims.append((time.time() - sent, sa))
    text = ", ".join("%02X at +%.2f s" % (sa, t) for t, sa in vcu_claims) or "none"
    if args.expect == "lost":
        cannot = [t for t, sa in vcu_claims if sa == 0xFE]
        others = [sa for _, sa in vcu_claims if sa != 0xFE]
        return bool(cannot) and cannot[0] < 1.0 and not others, (
               "kernel NAME %016X claimed %02X (higher priority): the VCU (NAME %016X) claimed %s (FE: Cannot Claim)"
               % (args.name, args.address, args.vcu_name, text)), peer
    others = [sa for _, sa in vcu_claims if sa != args.address]
    return args.address in [sa for _, sa in vcu_claims] and not others, (
           "kernel NAME %016X claimed %02X (lower priority): the VCU (NAME %016X) claimed %s"
           % (args.name, args.address, args.vcu_name, text))


def frames_after_loss(address, seconds):
    """(frames other than Address Claimed from ADDRESS, SHMs from any other address) on the
    wire (a raw CAN socket, extended frames) in SECONDS, as {CAN ID: count} each"""
    raw = socket.socket(socket.AF_CAN, socket.SOCK_RAW, socket.CAN_RAW)
    raw.setsockopt(socket.SOL_CAN_RAW, socket.CAN_RAW_FILTER,
                   struct.pack("=II", socket.CAN_EFF_FLAG, socket.CAN_EFF_FLAG))
    raw.bind((IF,))
    raw.settimeout(0.2)
    end, from_address, shms = time.time() + seconds, {}, {}
    while time.time() < end:
        try:
            frame = raw.recv(72)
        except socket.timeout:
            continue
        can_id = struct.unpack_from("=I", frame)[0] & socket.CAN_EFF_MASK
        sa, pf = can_id & 0xFF, (can_id >> 16) & 0xFF
        if sa == address and pf != PGN_CLAIM >> 8:
            from_address[can_id] = from_address.get(can_id, 0) + 1
        if pf == 0x0E and sa != address:  # SAE J1939-76 SHM, PGN 0x0E00
            shms[can_id] = shms.get(can_id, 0) + 1
    return from_address, shms


def ids_text(ids):
    return "%d (%s)" % (sum(ids.values()), " ".join("%08X" % i for i in sorted(ids)[:6]) + (" ..." if len(ids) > 6 else ""))


def diag(args):
    ok = report("j1939_dm1_bam", *cmd_dm1(argparse.Namespace(
        diagnostics=args.diagnostics, state=args.state, signal=args.signal, source=args.to, timeout=4)))
    for check, pgn, to in (("j1939_rts_cts_to_kernel", PGN_ECUID, args.to), ("j1939_bam_to_kernel", PGN_SOFT, 0xFF)):
        ok &= report(check, *cmd_request(argparse.Namespace(
            diagnostics=args.diagnostics, pgn=pgn, to=to, version=args.version, timeout=3)))
    return ok


def contest(args):
    ok = report("j1939_address_defend", *cmd_claim(argparse.Namespace(
        name=args.vcu_name + 1, address=args.address, vcu_name=args.vcu_name, expect="defend", timeout=2)))
    lost, text, peer = cmd_claim(argparse.Namespace(
        name=args.vcu_name - 1, address=args.address, vcu_name=args.vcu_name, expect="lost", timeout=1.5))
    from_address, shms = frames_after_loss(args.address, 1.0)
    lost = lost and not from_address and not shms
    text += "; then in 1 s: frames from %02X %s, SHMs from other addresses %s" % (
        args.address, ids_text(from_address), ids_text(shms))
    # the same claim three times more: the VCU, without an address, claims nothing
    watch = j1939_socket(pgn=PGN_CLAIM, promisc=True)
    watch.settimeout(0.2)
    for _ in range(3):
        peer.sendto((args.vcu_name - 1).to_bytes(8, "little"), (IF, socket.J1939_NO_NAME, PGN_CLAIM, 0xFF))
    end, again = time.time() + 1.0, []
    while time.time() < end:
        try:
            data, (_, _, _, sa) = watch.recvfrom(8)
        except socket.timeout:
            continue
        if data == args.vcu_name.to_bytes(8, "little"):
            again.append(sa)
    lost = lost and not again
    text += "; after 3 more claims the VCU claimed %s" % (" ".join("%02X" % a for a in again) or "nothing")
    return ok & report("j1939_address_lost", lost, text)


def number(text):
    return int(text, 0)


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = p.add_subparsers(dest="command", required=True)
    d = sub.add_parser("diag")
    d.add_argument("--diagnostics", required=True)
    d.add_argument("--state", required=True)
    d.add_argument("--signal", required=True)
    d.add_argument("--to", type=number, default=0x21)
    d.add_argument("--version", default="")
    c = sub.add_parser("contest")
    c.add_argument("--vcu-name", type=number, required=True)
    c.add_argument("--address", type=number, default=0x21)
    args = p.parse_args()
    ok = diag(args) if args.command == "diag" else contest(args)
    sys.exit(0 if ok else 1)


if __name__ == "__main__":
    main()
