#!/usr/bin/python3
"""Writes the installed VCU's /etc/openvcu configuration from the repository's HHEA example.

Called at build time by cmake/OpenvcuPackaging.cmake (and by hand the same way):
    make-etc-config.py SOURCE_DIR OUT_DIR
SOURCE_DIR is config/hhea; OUT_DIR receives vehicle.json, every file it names and
dashboard.json (openvcu.env is config/systemd/openvcu.env, copied by the CMake rule). The files are copied as they are except for the changes an installed VCU
needs (docs/design/packaging.md):
  * vehicle.json: the bus "vehicle" on "socketcan:can0" (the repository's is "sim:vehicle")
  * schedule.json: "overlay": "/var/lib/openvcu/schedule.overlay.json"
  * diagnostics.json: "countsFile": "/var/lib/openvcu/dtc_counts.json"
  * web.json: "dataFolder": "/var/lib/openvcu/web", "usersFile": "/etc/openvcu/web-users.json"
  (telemetry.json is copied as it is: its "queueFolder" is already /var/lib/openvcu/telemetry)
The edits are made in the text so that the files keep the repository's layout (an engineer can
diff them against /usr/share/openvcu/vehicles/hhea); each edited file is then parsed and
compared with the original plus the intended change, so an edit that missed fails the build.
"""
import json
import pathlib
import re
import sys

STATE = "/var/lib/openvcu"
BUS = ("vehicle", "socketcan:can0")


def fail(path, reason):
    sys.exit(f"make-etc-config.py: {path}: {reason}")


def load(path):
    try:
        return json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError) as error:
        fail(path, f"cannot read it as JSON: {error}")


def replace_value(path, text, key, old, new):
    """Replaces the one `"key": "old"` in text by `"key": "new"`."""
    pattern = re.compile(r'("' + re.escape(key) + r'"\s*:\s*)"' + re.escape(old) + '"')
    result, count = pattern.subn(lambda m: m.group(1) + json.dumps(new), text)
    if count != 1:
        fail(path, f'expected exactly one "{key}": "{old}", found {count}')
    return result


def insert_first_key(path, text, key, value):
    """Adds `"key": value,` as the first member of the top-level object."""
    match = re.match(r'\s*\{[ \t]*\n', text)
    if not match:
        fail(path, "does not start with an object")
    return text[:match.end()] + f'  {json.dumps(key)}: {json.dumps(value)},\n' + text[match.end():]


def main():
    if len(sys.argv) != 3:
        sys.exit("usage: make-etc-config.py SOURCE_DIR OUT_DIR")
    source, out = pathlib.Path(sys.argv[1]), pathlib.Path(sys.argv[2])
    vehicle_path = source / "vehicle.json"
    vehicle = load(vehicle_path)

    # the files vehicle.json names (relative to its folder), and the HMI's dashboard.json beside it
    names = list(vehicle.get("dbc", []))
    for key in ("schedule", "receive", "fsm", "gpio", "simulation", "diagnostics", "web", "telemetry", "safety"):
        if isinstance(vehicle.get(key), str):
            names.append(vehicle[key])
    names.append("dashboard.json")
    for name in names:
        if pathlib.PurePath(name).is_absolute() or "/" in name:
            fail(vehicle_path, f"'{name}': expected a file beside vehicle.json")
        if not (source / name).is_file():
            fail(source / name, "named by vehicle.json (or the dashboard) but missing")

    # changes: file -> (text edit, expected parsed result from the original)
    def edit_vehicle(path, text, data):
        buses = [bus for bus in data.get("buses", []) if bus.get("name") == BUS[0]]
        if len(buses) != 1:
            fail(path, f"expected one bus named '{BUS[0]}'")
        text = replace_value(path, text, "link", buses[0]["link"], BUS[1])
        buses[0]["link"] = BUS[1]
        return text, data

    def edit_schedule(path, text, data):
        if "overlay" in data:
            text = replace_value(path, text, "overlay", data["overlay"], f"{STATE}/schedule.overlay.json")
        else:
            text = insert_first_key(path, text, "overlay", f"{STATE}/schedule.overlay.json")
        data = {"overlay": f"{STATE}/schedule.overlay.json", **{k: v for k, v in data.items() if k != "overlay"}}
        return text, data

    def edit_diagnostics(path, text, data):
        text = replace_value(path, text, "countsFile", data.get("countsFile", ""), f"{STATE}/dtc_counts.json")
        data["countsFile"] = f"{STATE}/dtc_counts.json"
        return text, data

    def edit_web(path, text, data):
        text = replace_value(path, text, "dataFolder", data.get("dataFolder", ""), f"{STATE}/web")
        text = replace_value(path, text, "usersFile", data.get("usersFile", ""), "/etc/openvcu/web-users.json")
        data["dataFolder"] = f"{STATE}/web"
        data["usersFile"] = "/etc/openvcu/web-users.json"
        return text, data

    edits = {"vehicle.json": edit_vehicle}
    for key, edit in (("schedule", edit_schedule), ("diagnostics", edit_diagnostics), ("web", edit_web)):
        if not isinstance(vehicle.get(key), str):
            fail(vehicle_path, f'no "{key}" file: the installed configuration changes it')
        edits[vehicle[key]] = edit

    out.mkdir(parents=True, exist_ok=True)
    for name in ["vehicle.json"] + names:
        path = source / name
        text = path.read_text(encoding="utf-8")
        if name in edits:
            text, expected = edits[name](path, text, load(path))
            try:
                written = json.loads(text)
            except ValueError as error:
                fail(path, f"the edited text is no longer JSON: {error}")
            if written != expected:
                fail(path, "the edited file differs from the intended change")
        (out / name).write_text(text, encoding="utf-8")


if __name__ == "__main__":
    main()
