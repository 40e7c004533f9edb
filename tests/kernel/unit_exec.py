#!/usr/bin/python3
"""Turns installed systemd service units into shell scripts that start the service the way
systemd would, for the install test's VM (guest-install.sh), whose PID 1 is not systemd.

    unit_exec.py OUTDIR UNIT_FILE...

For each UNIT_FILE (e.g. /lib/systemd/system/openvcu-can-tx.service) writes OUTDIR/NAME.sh
(NAME = the unit's name without ".service") and prints one line "NAME: user U, caps C,
not emulated: D..." to stdout. NAME.sh creates RuntimeDirectory/StateDirectory (owner and
mode as systemd does), then in a private mount namespace makes the file system read-only
as ProtectSystem= says (ReadWritePaths=, the runtime and state directories stay writable)
and hides /home, /root and /run/user (ProtectHome=yes), then runs ExecStart with a clean
environment (Environment=, EnvironmentFile=, HOME/USER/..., RUNTIME_DIRECTORY,
STATE_DIRECTORY), UMask=, as User=/Group= with supplementary groups, NoNewPrivileges=,
AmbientCapabilities= and CapabilityBoundingSet= (setpriv). ${VAR} and $VAR in ExecStart are
expanded as systemd does (a lone $VAR word splits on whitespace).

Directives that only restrict further and that this does not reproduce (RestrictAddressFamilies,
DeviceAllow, ProtectKernelModules, ...) are named in the summary line; a directive it does not
know at all is an error (exit 1, file and directive named), so a new unit setting is never
silently ignored. Exit 2 on bad arguments or an unreadable unit.
"""
import pathlib
import pwd
import re
import shlex
import sys

# restrictions the VM run does not reproduce: named in the summary, never silently dropped
NOT_EMULATED = {"RestrictAddressFamilies", "DeviceAllow", "ProtectKernelModules",
                "ProtectControlGroups", "ProtectKernelTunables", "PrivateTmp", "PrivateDevices",
                "LockPersonality", "RestrictRealtime", "SystemCallFilter", "MemoryDenyWriteExecute"}
# supervision and ordering: no meaning for a single start
IGNORED = {"Description", "Documentation", "PartOf", "Requires", "Wants", "After", "Before",
           "WantedBy", "Type", "NotifyAccess", "Restart", "RestartSec", "WatchdogSec",
           "TimeoutStopSec", "TimeoutStartSec", "StartLimitIntervalSec", "StartLimitBurst",
           "RuntimeDirectoryPreserve", "KillMode", "KillSignal", "StandardOutput", "StandardError",
           "SyslogIdentifier", "ConditionPathExists", "BindsTo", "Alias"}
HANDLED = {"User", "Group", "SupplementaryGroups", "UMask", "ExecStart", "Environment",
           "EnvironmentFile", "WorkingDirectory", "NoNewPrivileges", "AmbientCapabilities",
           "CapabilityBoundingSet", "ProtectSystem", "ProtectHome", "ReadWritePaths",
           "RuntimeDirectory", "RuntimeDirectoryMode", "StateDirectory", "StateDirectoryMode"}
API_FILESYSTEMS = ("/dev", "/proc", "/sys")


def fail(path, reason, code=1):
    sys.exit(f"unit_exec.py: {path}: {reason}")


def parse_unit(path):
    """[(section, key, value)] in file order; continuation lines joined."""
    try:
        lines = path.read_text(encoding="utf-8").splitlines()
    except OSError as error:
        fail(path, f"cannot read: {error}", 2)
    entries, section, pending = [], None, ""
    for number, raw in enumerate(lines, 1):
        line = pending + raw.strip()
        pending = ""
        if line.endswith("\\"):
            pending = line[:-1] + " "
            continue
        if not line or line[0] in "#;":
            continue
        if line.startswith("["):
            section = line.strip("[]")
            continue
        if "=" not in line:
            fail(path, f"line {number}: not key=value: {line}")
        key, value = line.split("=", 1)
        entries.append((section, key.strip(), value.strip()))
    return entries


def read_environment_file(path, unit):
    optional = path.startswith("-")
    path = path.lstrip("-")
    try:
        text = pathlib.Path(path).read_text(encoding="utf-8")
    except OSError as error:
        if optional:
            return {}
        fail(unit, f"EnvironmentFile {path}: {error}")
    env = {}
    for line in text.splitlines():
        line = line.strip()
        if not line or line[0] in "#;":
            continue
        if "=" not in line:
            fail(unit, f"EnvironmentFile {path}: not KEY=VALUE: {line}")
        key, value = line.split("=", 1)
        value = value.strip()
        if len(value) >= 2 and value[0] == value[-1] and value[0] in "'\"":
            value = value[1:-1]
        env[key.strip()] = value
    return env


def expand(words, env, unit):
    """systemd's ExecStart expansion: ${VAR} in place, a lone $VAR word split on whitespace."""
    out = []
    for word in words:
        lone = re.fullmatch(r"\$([A-Za-z_][A-Za-z0-9_]*)", word)
        if lone:
            out.extend(env.get(lone.group(1), "").split())
            continue
        def value(match):
            if match.group(1) not in env:
                fail(unit, f"ExecStart names ${{{match.group(1)}}}, which no Environment sets")
            return env[match.group(1)]
        out.append(re.sub(r"\$\{([A-Za-z_][A-Za-z0-9_]*)\}", value, word))
    return out


def capabilities(value):
    """'CAP_SYS_NICE CAP_NET_RAW' -> 'sys_nice,net_raw' (setpriv's spelling)."""
    return ",".join(cap.lower().removeprefix("cap_") for cap in value.split())


def script_for(path):
    entries = parse_unit(path)
    service = {}
    not_emulated = []
    for section, key, value in entries:
        if key in IGNORED:
            continue
        if key in NOT_EMULATED:
            not_emulated.append(key)
            continue
        if section != "Service" or key not in HANDLED:
            fail(path, f"[{section}] {key}= is not known to unit_exec.py (add it, or name it as not emulated)")
        service.setdefault(key, []).append(value)

    def one(key, default=None):
        values = service.get(key)
        return values[-1] if values else default

    if not service.get("ExecStart"):
        fail(path, "no ExecStart=")
    if len(service["ExecStart"]) != 1:
        fail(path, "more than one ExecStart= (only Type=oneshot allows that)")
    user = one("User", "root")
    group = one("Group")
    try:
        account = pwd.getpwnam(user)
    except KeyError:
        fail(path, f"User={user}: no such user (did the package's postinst create it?)")

    env = {"PATH": "/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin", "LANG": "C.UTF-8",
           "HOME": account.pw_dir, "USER": user, "LOGNAME": user, "SHELL": account.pw_shell}
    for value in service.get("Environment", []):
        for assignment in shlex.split(value):
            key, _, val = assignment.partition("=")
            env[key] = val
    for value in service.get("EnvironmentFile", []):
        env.update(read_environment_file(value, path))

    setup = []
    writable = [p for value in service.get("ReadWritePaths", []) for p in value.split()]
    for kind, base, mode_key, default_mode in (("RuntimeDirectory", "/run", "RuntimeDirectoryMode", "0755"),
                                               ("StateDirectory", "/var/lib", "StateDirectoryMode", "0755")):
        names = [n for value in service.get(kind, []) for n in value.split()]
        mode = one(mode_key, default_mode)
        for name in names:
            folder = f"{base}/{name}"
            setup.append(f"install -d -o {shlex.quote(user)} -g {shlex.quote(group or user)} -m {mode} {shlex.quote(folder)}")
            writable.append(folder)
        if names:
            env["RUNTIME_DIRECTORY" if kind == "RuntimeDirectory" else "STATE_DIRECTORY"] = ":".join(f"{base}/{n}" for n in names)

    exec_line = service["ExecStart"][0]
    ignore_failure = exec_line.startswith("-")
    exec_line = exec_line.lstrip("-")
    if exec_line[:1] in "@:+!":
        fail(path, f"ExecStart prefix '{exec_line[0]}' is not supported")
    argv = expand(shlex.split(exec_line), env, path)
    if not argv[0].startswith("/"):
        fail(path, f"ExecStart {argv[0]}: not an absolute path")

    # systemd sets the supplementary groups from User= (initgroups); without User= it runs as
    # root with none but SupplementaryGroups=
    priv = ["setpriv", f"--reuid={user}", f"--regid={group or account.pw_gid}",
            "--init-groups" if one("User") else "--clear-groups"]
    if service.get("SupplementaryGroups"):
        fail(path, "SupplementaryGroups= is not supported by unit_exec.py")
    if one("NoNewPrivileges", "no") in ("yes", "true", "1", "on"):
        priv.append("--no-new-privs")
    ambient = capabilities(" ".join(service.get("AmbientCapabilities", [])))
    if ambient:
        plus = ",".join("+" + c for c in ambient.split(","))
        priv += [f"--inh-caps={plus}", f"--ambient-caps={plus}"]
    bounding = capabilities(" ".join(service.get("CapabilityBoundingSet", [])))
    if bounding:
        priv.append("--bounding-set=-all," + ",".join("+" + c for c in bounding.split(",")))
    umask = one("UMask", "0022")
    workdir = one("WorkingDirectory", "/")
    run = (["env", "-i"] + [f"{k}={v}" for k, v in env.items()] + priv
           + ["--", "/bin/sh", "-c", f"umask {umask} && cd {shlex.quote(workdir)} && exec \"$@\"", "sh"] + argv)

    # the mount namespace: ProtectSystem / ProtectHome as systemd sets them up
    protect = one("ProtectSystem", "no")
    ns = []
    if protect not in ("no", "false"):
        readonly = {"strict": None, "full": ["/usr", "/boot", "/efi", "/etc"],
                    "yes": ["/usr", "/boot", "/efi"], "true": ["/usr", "/boot", "/efi"]}.get(protect, False)
        if readonly is False:
            fail(path, f"ProtectSystem={protect}: unknown value")
        ns.append("mounts=$(findmnt -rno TARGET)")
        for folder in writable:
            # its own mount (unless it is one already), so that the read-only remounts skip it
            ns.append(f"findmnt -rno TARGET {shlex.quote(folder)} >/dev/null || mount --bind {shlex.quote(folder)} {shlex.quote(folder)}")
        keep = " ".join(shlex.quote(f) for f in writable)
        if readonly is None:   # strict: every mount but the API file systems and the writable paths
            ns.append("for m in $mounts; do m=$(printf '%b' \"$m\"); case $m in /dev|/dev/*|/proc|/proc/*|/sys|/sys/*) continue;; esac; "
                      f"for w in {keep}; do [ \"$m\" = \"$w\" ] && continue 2; done; "
                      "mount -o remount,bind,ro \"$m\" 2>/dev/null || mount --bind -o ro \"$m\" \"$m\"; done")
        else:
            for folder in readonly:
                ns.append(f"[ -d {folder} ] && mount --bind {folder} {folder} && mount -o remount,bind,ro {folder}")
    if one("ProtectHome", "no") in ("yes", "true"):
        for folder in ("/home", "/root", "/run/user"):
            ns.append(f"if [ -d {folder} ]; then mount -t tmpfs -o mode=000,size=4k tmpfs {folder}; fi")
    elif one("ProtectHome", "no") not in ("no", "false"):
        fail(path, f"ProtectHome={one('ProtectHome')}: only yes/no are supported")

    lines = [
        "#!/bin/bash",
        f"# generated by tests/kernel/unit_exec.py from {path}: starts the service as systemd would",
        "set -euo pipefail",
        *setup,
    ]
    inner = "\n".join(ns + ["exec " + shlex.join(run)])
    if ns:
        lines.append("exec unshare --mount --propagation private -- /bin/bash -euc " + shlex.quote(inner))
    else:
        lines.append("exec " + shlex.join(run))
    summary = (f"user {user}:{group or account.pw_gid}, caps {ambient or 'none'}, ProtectSystem={protect}"
               f"{', exit status ignored' if ignore_failure else ''}"
               f"{', not emulated: ' + ' '.join(sorted(set(not_emulated))) if not_emulated else ''}")
    return "\n".join(lines) + "\n", summary


def main():
    if len(sys.argv) < 3:
        sys.exit("usage: unit_exec.py OUTDIR UNIT_FILE...")
    out = pathlib.Path(sys.argv[1])
    out.mkdir(parents=True, exist_ok=True)
    for unit in sys.argv[2:]:
        path = pathlib.Path(unit)
        if not path.name.endswith(".service"):
            fail(path, "not a .service unit", 2)
        text, summary = script_for(path)
        script = out / (path.name.removesuffix(".service") + ".sh")
        script.write_text(text, encoding="utf-8")
        script.chmod(0o755)
        print(f"{path.name.removesuffix('.service')}: {summary}")


if __name__ == "__main__":
    main()
