#!/usr/bin/env python3
"""Another J1939 node on vcan0, made of the kernel's can-j1939 sockets (no project code):
the VM test's independent view of the VCU as a J1939 network citizen (issue 24).

  j1939_peer.py dm1 --diagnostics FILE --state NAME --signal KEY
      receive the VCU's DM1 (PGN 0xFECA) as the kernel delivers it (a BAM reassembled by the
      kernel when longer than 8 bytes) and find the DTCs that diagnostics.json maps to the FSM
      state NAME and to the signal KEY (SPN and FMI read from the file, not hard-coded)
  j1939_peer.py request --diagnostics FILE --pgn 64965|65242 --to ADDR [--version V]
      a socket at 0xF9 sends a Request (PGN 0xEA00) for the PGN to ADDR (0xFF: global) and
      receives the answer reassembled by the kernel (RTS/CTS to 0xF9, the kernel sends CTS and
      EndOfMsgAck; BAM for a global request); the content must equal the '*'-terminated fields
      of diagnostics.json's identification (SOFT: plus the field "openvcu VERSION" the service
      appends; VERSION as given by --version, else any text without '*')
  j1939_peer.py claim --name N --address A --vcu-name M --expect yield|defend [--range LO HI]
      a kernel socket with NAME N claims address A (the kernel sends the Address Claimed when
      the socket sends PGN 0xEE00 with its NAME); watches the Address Claimed messages of the
      VCU's NAME M: yield = the VCU claims another address in LO..HI; defend = the VCU claims
      A again and no other address

Prints one line starting with PASS or FAIL, exit 0 on PASS, 1 on FAIL.
"""
import argparse
import json
import socket
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


def finish(ok, text):
    print(("PASS " if ok else "FAIL ") + text, flush=True)
    sys.exit(0 if ok else 1)


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
        finish(False, "diagnostics.json maps %s / %s to %d DTCs, want 2" % (args.state, args.signal, len(want)))
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
            finish(len(data) > 8, "kernel delivered DM1 from SA %02X, %d bytes (%s), DTCs %s contain %s"
                   % (sa, len(data), "BAM reassembled" if len(data) > 8 else "single frame: no BAM", got, want))
    finish(False, "no DM1 with %s within %.0f s; seen: %s" % (want, args.timeout, " | ".join(seen[-4:]) or "none"))


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
        finish(False, "unsupported PGN %d" % args.pgn)
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
        finish(data == want and len(data) > 8,
               "request PGN %d to %02X -> kernel delivered %d bytes from SA %02X (%s): %r%s"
               % (args.pgn, args.to, len(data), sa, how, data, "" if data == want else " != expected %r" % want))
    finish(False, "no answer for PGN %d from %02X within %.0f s (want %r)" % (args.pgn, args.to, args.timeout, want))


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
            if args.expect == "yield" and args.low <= sa <= args.high:
                break
    text = ", ".join("%02X at +%.2f s" % (sa, t) for t, sa in vcu_claims) or "none"
    if args.expect == "yield":
        moved = [sa for _, sa in vcu_claims if args.low <= sa <= args.high]
        finish(bool(moved), "kernel NAME %016X claimed %02X: the VCU (NAME %016X) claimed %s%s"
               % (args.name, args.address, args.vcu_name, text, "; NEWADDR=%02X" % moved[0] if moved else ""))
    others = [sa for _, sa in vcu_claims if sa != args.address]
    finish(args.address in [sa for _, sa in vcu_claims] and not others,
           "kernel NAME %016X claimed %02X (lower priority): the VCU (NAME %016X) claimed %s"
           % (args.name, args.address, args.vcu_name, text))


def number(text):
    return int(text, 0)


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = p.add_subparsers(dest="command", required=True)
    d = sub.add_parser("dm1")
    d.add_argument("--diagnostics", required=True)
    d.add_argument("--state", required=True)
    d.add_argument("--signal", required=True)
    d.add_argument("--source", type=number, default=0x21)
    d.add_argument("--timeout", type=float, default=3)
    r = sub.add_parser("request")
    r.add_argument("--diagnostics", required=True)
    r.add_argument("--pgn", type=number, required=True)
    r.add_argument("--to", type=number, default=0x21)
    r.add_argument("--version", default="")
    r.add_argument("--timeout", type=float, default=3)
    c = sub.add_parser("claim")
    c.add_argument("--name", type=number, required=True)
    c.add_argument("--address", type=number, required=True)
    c.add_argument("--vcu-name", type=number, required=True)
    c.add_argument("--expect", choices=("yield", "defend"), required=True)
    c.add_argument("--range", type=number, nargs=2, default=(128, 247), metavar=("LO", "HI"))
    c.add_argument("--timeout", type=float, default=2)
    args = p.parse_args()
    if args.command == "claim":
        args.low, args.high = args.range
    {"dm1": cmd_dm1, "request": cmd_request, "claim": cmd_claim}[args.command](args)


if __name__ == "__main__":
    main()
