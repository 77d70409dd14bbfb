#!/usr/bin/env python3
"""Which process of a deployment publishes and subscribes which LCM channel.

Reads a deployment file (config/deploy/*.deploy) and, for every process in it, the [channels]
section of the config that process runs with (its --config, else config/<program>.ini), and prints
a Markdown table (process -> channels published / subscribed) and a Mermaid `graph LR` block.

  tools/docs/channel_graph.py [DEPLOYMENT]                  print the block (default config/deploy/demo.deploy)
  tools/docs/channel_graph.py [DEPLOYMENT] --write README.md  replace the block between the markers
  tools/docs/channel_graph.py [DEPLOYMENT] --check README.md  exit 1 with a diff if it differs

Channel names come from the configs; what a process does with each [channels] key (publish or
subscribe, and under which option) is written below in ROLES, after the node constructors in
processes/<name>/. A key that ROLES does not know is an error, so a new channel cannot be left out.
Standard library only; INI and deployment files are read with the rules of glue::IniFile.
"""

import argparse
import difflib
import os
import re
import shlex
import sys

BEGIN = "<!-- BEGIN channel-graph"
END = "<!-- END channel-graph -->"

SUB, PUB = "sub", "pub"


def _always(_cfg):
    return True


def _never(_cfg):
    """A [channels] key that names a channel another key subscribes already (no edge of its own)."""
    return False


def _opt(section, key, *values):
    """Condition: [section] key is one of values (strings as written in the INI)."""
    return lambda cfg: cfg.get(section, key) in values


def _flag_or_opt(flag, section, key, *values):
    """Condition on an option a command-line flag overrides (placecells --mode)."""
    return lambda cfg: (cfg.flags.get(flag) or cfg.get(section, key)) in values


def _positive(section, key):
    return lambda cfg: float(cfg.get(section, key)) > 0


def _true(section, key):
    return lambda cfg: cfg.get(section, key) in ("true", "1", "yes", "on")


# program -> {[channels] key: (direction, condition)}: what the node's constructor subscribes and
# what it publishes (processes/<dir>/<dir>_node.cpp).
ROLES = {
    "dead-reckoning": {"odometry": (SUB, _always), "pose": (PUB, _always)},
    "laser-slam": {  # --mode localize: the pose, its status and the saved map instead of SLAM's map and status
        "odometry": (SUB, _always), "scan": (SUB, _always), "pose": (PUB, _always),
        "map": (PUB, lambda cfg: cfg.flags.get("mode") != "localize"),
        "status": (PUB, lambda cfg: cfg.flags.get("mode") != "localize"),
        "grid": (PUB, _always), "grid_request": (SUB, _always),
        "correction": (PUB, lambda cfg: cfg.flags.get("mode") != "localize"
                       and cfg.get("laser_slam", "backend") == "graph"),
        "localization_status": (PUB, lambda cfg: cfg.flags.get("mode") == "localize"),
    },
    "fused-slam": {
        "odometry": (SUB, _always), "scan": (SUB, _always), "visual": (SUB, _always),
        "pose": (PUB, _always), "map": (PUB, _always), "status": (PUB, _always),
    },
    "navigator": {
        "odometry": (SUB, _always), "pose": (SUB, _always), "homing_vector": (SUB, _always),
        "route": (SUB, _always), "drive_command": (PUB, _always), "status": (PUB, _always),
    },
    "homing": {
        "omni": (SUB, _opt("homing", "input", "raw")),
        "panorama": (SUB, _opt("homing", "input", "panorama")),
        "home_snapshot": (SUB, _opt("homing", "input", "raw", "panorama")),
        "landmarks": (SUB, _opt("homing", "input", "landmarks")),
        "home_landmarks": (SUB, _opt("homing", "input", "landmarks")),
        "homing_vector": (PUB, _always),
    },
    "landmarks": {
        "omni": (SUB, _opt("landmarks", "input", "raw")),
        "panorama": (SUB, _opt("landmarks", "input", "panorama")),
        "landmarks": (PUB, _always),  # %s: the method (--method overrides [landmarks] method)
    },
    "placecells": {
        "omni": (SUB, _opt("placecells", "input", "raw")),
        "panorama": (SUB, _opt("placecells", "input", "panorama")),
        "odometry": (SUB, _always),
        "explore_pose": (SUB, _flag_or_opt("mode", "placecells", "mode", "explore")),
        "explore_correction": (SUB, _flag_or_opt("mode", "placecells", "mode", "explore")),
        "match": (PUB, _always),
        "pose": (PUB, _flag_or_opt("mode", "placecells", "mode", "localize")),
    },
    "ratslam": {
        "omni": (SUB, _opt("node", "input", "raw")),
        "panorama": (SUB, _opt("node", "input", "panorama")),
        "odometry": (SUB, _always),
        "pose": (PUB, _always),
        "experience_map": (PUB, _positive("node", "experience_map_interval_s")),
    },
    "sim": {
        "omni": (PUB, _true("camera", "publish_raw")),
        "panorama": (PUB, _true("camera", "publish_panorama")),
        "scan": (PUB, _always), "odometry": (PUB, _always), "ground_truth": (PUB, _always),
        "drive_command": (SUB, _flag_or_opt("drive", "sim", "drive", "commands")),
    },
    "viewer": {  # poses and landmarks are regular expressions (LCM's, anchored)
        "point_map": (SUB, _always), "poses": (SUB, _always), "ground_truth": (SUB, _always),
        "panorama": (SUB, _always), "omni": (SUB, _always), "landmarks": (SUB, _always),
        "homing_vector": (SUB, _always), "place_cell_match": (SUB, _always), "scan": (SUB, _always),
        "grid": (SUB, _always), "laser_slam_status": (SUB, _always),
        "laser_slam_pose": (SUB, _never),  # which trail a correction breaks: `poses` subscribes it
        "laser_slam_correction": (SUB, _always),
    },
    "omni-camera": {"frame": (PUB, _always)},
    "laser-hokuyo": {"scan": (PUB, _always)},
}
# [channels] keys whose value is a regular expression.
REGEX_KEYS = {("viewer", "poses"), ("viewer", "landmarks")}
# Channel keys a command-line flag overrides: (program, key) -> flag (navigator --fixes POSE_EKF).
CHANNEL_FLAGS = {("navigator", "pose"): "fixes"}

# Recorders: they subscribe to a regex (--channel, both; every channel by default).
RECORDERS = {"recorder": "channel", "lcm-logger": "channel"}
# Programs without a [channels] config: what they do on the bus.
OTHER = {
    "recorder": "records every channel",
    "lcm-logger": "records every channel",
    "gridgen": "no bus: writes the grid database and its log (`--out`)",
    "calibrate-mirror": "no bus: reads the grid's log (`--log`), writes the `[mirror]` calibration and the mask",
    "replay": "no bus: runs the `--only` processes over a log in-process, writes their outputs and its inputs (`--out`)",
}


class Error(Exception):
    pass


class Ini:
    """An INI file read as glue::IniFile reads it: sections, `key = value`, `#`/`;` comments."""

    def __init__(self, path, display):
        self.path = path
        self.display = display
        self.sections = {}  # section -> {key: (value, line)}
        self.section_lines = {}
        self.order = []
        try:
            with open(path, encoding="utf-8") as f:
                lines = f.read().split("\n")
        except OSError as e:
            raise Error(f"{display}: cannot read: {e.strerror}")
        section = None
        for n, raw in enumerate(lines, 1):
            t = raw.strip()
            if not t or t[0] in "#;":
                continue
            if t[0] == "[":
                if t[-1] != "]":
                    raise Error(f"{display}:{n}: malformed section header '{t}'")
                section = t[1:-1].strip()
                if section not in self.sections:
                    self.sections[section] = {}
                    self.section_lines[section] = n
                    self.order.append(section)
                continue
            if "=" not in t or section is None:
                raise Error(f"{display}:{n}: expected 'key = value' in a [section], got '{t}'")
            key, value = t.split("=", 1)
            key, value = key.strip(), value.strip()
            for c in (" #", " ;", "\t#", "\t;"):
                p = value.find(c)
                if p >= 0:
                    value = value[:p].strip()
            self.sections[section][key] = (value, n)

    def get(self, section, key):
        try:
            return self.sections[section][key][0]
        except KeyError:
            raise Error(f"{self.display}: missing [{section}] {key}")


class ProcessConfig:
    """A process's config file and the flags of its command that override it."""

    def __init__(self, ini, flags):
        self.ini = ini
        self.flags = flags

    def get(self, section, key):
        return self.ini.get(section, key)


def parse_flags(args):
    flags = {}
    i = 0
    while i < len(args):
        a = args[i]
        if a.startswith("--"):
            if "=" in a:
                k, v = a[2:].split("=", 1)
            elif i + 1 < len(args) and not args[i + 1].startswith("--"):
                k, v = a[2:], args[i + 1]
                i += 1
            else:
                k, v = a[2:], ""
            flags[k] = v
        i += 1
    return flags


def substitute(text, variables, depth=0):
    """${name} -> value for the variables given; others stay as written; $$ is a literal $."""
    if depth > 20:
        raise Error(f"variables refer to each other in a loop: '{text}'")

    def one(m):
        if m.group(0) == "$$":
            return "$"
        name = m.group(1)
        return substitute(variables[name], variables, depth + 1) if name in variables else m.group(0)
    return re.sub(r"\$\$|\$\{([A-Za-z_][A-Za-z0-9_]*)\}", one, text)


def rel(root, path):
    r = os.path.relpath(path, root)
    return path if r.startswith("..") else r


def read_deployment(root, deploy_rel, given=None, prefix=""):
    deploy = Ini(os.path.join(root, deploy_rel), deploy_rel)
    defaults = deploy.sections.get("defaults", {})
    config_dir = os.path.join(root, "config")
    # The file's [variables], ${config} and ${root} are resolved (the configs are read); the other
    # built-in variables (${out}, ${bin}, ...) are shown as written. An included file's variables
    # are the including section's keys (`given`).
    variables = {k: v for k, (v, _) in deploy.sections.get("variables", {}).items()}
    variables.update(given or {})
    variables.update({"config": config_dir, "root": root})
    processes = []
    for section in deploy.order:
        if section.startswith("include "):
            # [include NAME]: another deployment file's processes, named NAME.PROCESS (launch's rule).
            inc = section[len("include "):].strip()
            keys = deploy.sections[section]
            if "file" not in keys:
                raise Error(f"{deploy_rel}:{deploy.section_lines[section]}: [{section}]: no file")
            inc_rel = os.path.normpath(os.path.join(os.path.dirname(deploy_rel), keys["file"][0]))
            inc_vars = {k: substitute(v, variables) for k, (v, _) in keys.items() if k not in ("file", "processes")}
            processes += read_deployment(root, inc_rel, inc_vars, prefix + inc + ".")
            continue
        if not section.startswith("process "):
            continue
        name = prefix + section[len("process "):].strip()
        keys = deploy.sections[section]
        where = f"{deploy_rel}:{deploy.section_lines[section]}: [{section}]"
        if "command" not in keys:
            raise Error(f"{where}: no command")
        group = keys.get("group", defaults.get("group", ("", 0)))[0]
        try:
            words = [substitute(w, variables) for w in shlex.split(keys["command"][0], comments=False)]
        except ValueError as e:
            raise Error(f"{deploy_rel}:{keys['command'][1]}: command: {e}")
        program = words[0].replace("${bin}/", "")
        flags = parse_flags(words[1:])
        p = {"name": name, "group": group, "program": program, "flags": flags, "where": where,
             "pub": [], "sub": [], "regex": [], "note": ""}
        url = flags.get("lcm-url", "")
        if url.startswith("file://"):
            path = url.split('?')[0][len('file://'):]
            writes = "mode=w" in url.split('?', 1)[-1].split('&')
            p["note"] = f"writes `{path}`, not the bus" if writes else f"reads `{path}`, not the bus"
        if program in OTHER:
            p["note"] = OTHER[program]
            if program in RECORDERS:
                regex = flags.get(RECORDERS[program], ".*")
                p["regex"].append(regex)
                if regex != ".*":
                    p["note"] = f"records `{regex}`"
            p["config"] = ""
        elif program in ROLES:
            read_channels(root, config_dir, p)
        else:
            raise Error(f"{where}: program '{program}' is not known to tools/docs/channel_graph.py "
                        "(add it to ROLES or OTHER)")
        processes.append(p)
    return processes


def read_channels(root, config_dir, p):
    program = p["program"]
    path = p["flags"].get("config") or os.path.join(config_dir, program.replace("-", "_") + ".ini")
    ini = Ini(path, rel(root, path))
    p["config"] = ini.display
    cfg = ProcessConfig(ini, p["flags"])
    prefix = p["flags"].get("channel-prefix", "")
    channels = ini.sections.get("channels")
    if channels is None:
        raise Error(f"{ini.display}: no [channels] section ({p['where']})")
    roles = ROLES[program]
    for key, (value, line) in channels.items():
        if key not in roles:
            raise Error(f"{ini.display}:{line}: [channels] {key}: not known to tools/docs/channel_graph.py "
                        f"for {program} (add it to ROLES with its direction)")
    for key, (direction, condition) in roles.items():
        if key not in channels:
            raise Error(f"{ini.display}: missing [channels] {key} ({program})")
        if not condition(cfg):
            continue
        flag = CHANNEL_FLAGS.get((program, key))
        channel = prefix + (p["flags"][flag] if flag and p["flags"].get(flag) else channels[key][0])
        if program == "landmarks" and "%s" in channel:
            method = p["flags"].get("method") or cfg.get("landmarks", "method")
            channel = channel.replace("%s", method.upper())
        if (program, key) in REGEX_KEYS:
            p["regex"].append(channel)
        else:
            p[direction].append(channel)


def on_bus(p):
    return not p["note"] or p["program"] in RECORDERS


def code(items):
    return ", ".join(f"`{c}`" for c in items)


def render(processes, deploy_rel):
    published = []
    for p in processes:
        if on_bus(p):
            published += [c for c in p["pub"] if c not in published]
    out = [f"{BEGIN}: generated by tools/docs/channel_graph.py from {deploy_rel} and the processes' "
           "[channels]; do not edit by hand (ctest readme_channel_graph_current) -->", ""]
    out.append("| process | group | config | publishes | subscribes |")
    out.append("|---|---|---|---|---|")
    for p in processes:
        subs = code(p["sub"])
        for r in p["regex"]:
            if r == ".*":
                matched = "every channel"
            else:
                hits = [c for c in published if re.fullmatch(r, c)]
                matched = code(hits) if hits else "none in this deployment"
            subs += (", " if subs else "") + f"`{r}` ({matched})"
        if p["note"]:
            subs = (subs + "; " if subs else "") + p["note"]
        config = f"`{p['config']}`" if p["config"] else "-"
        out.append(f"| `{p['name']}` | {p['group']} | {config} | {code(p['pub']) or '-'} | {subs or '-'} |")
    out += ["", "```mermaid", "graph LR"]

    def pid(name):
        return "p_" + re.sub(r"[^A-Za-z0-9]", "_", name)

    def inputs_of(p):
        inputs = []
        for c in p["sub"] + [h for r in p["regex"] for h in
                             ([c for c in published if re.fullmatch(r, c)] or [r])]:
            if c not in inputs:
                inputs.append(c)
        return inputs

    def cid(channel):
        return re.sub(r"[^A-Za-z0-9_]", "_", channel)

    graph = [p for p in processes if on_bus(p) and p["program"] not in RECORDERS]
    channels = []
    for p in graph:
        out.append(f"  {pid(p['name'])}[{p['name']}]")
        channels += [c for c in p["pub"] + inputs_of(p) if c not in channels]
    for p in graph:
        if p["pub"]:
            out.append(f"  {pid(p['name'])} --> " + " & ".join(cid(c) for c in p["pub"]))
    for p in graph:
        inputs = inputs_of(p)
        for arrow, chosen in (("-->", [c for c in inputs if c in published]),
                              ("-.->", [c for c in inputs if c not in published])):
            if chosen:
                out.append("  " + " & ".join(cid(c) for c in chosen) + f" {arrow} {pid(p['name'])}")
    out.append("  classDef channel fill:#eef3ff,stroke:#6b7fb3")
    out.append("  class " + ",".join(cid(c) for c in channels) + " channel")
    out.append("```")
    out.append("")
    out.append("Processes are white, channels blue; a dotted arrow: nothing in this deployment "
               "publishes that channel (an input a lab may send). The recorder records every channel "
               "and is left out of the picture.")
    out.append("")
    out.append(END)
    return "\n".join(out) + "\n"


def find_block(text, path):
    b = text.find(BEGIN)
    e = text.find(END)
    if b < 0 or e < 0 or e < b:
        raise Error(f"{path}: no block between '{BEGIN} ...' and '{END}'")
    return b, e + len(END) + (1 if text[e + len(END):e + len(END) + 1] == "\n" else 0)


def main(argv):
    here = os.path.dirname(os.path.abspath(__file__))
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter,
                                 epilog="\n\n".join(__doc__.split("\n\n")[1:]))
    ap.add_argument("deployment", nargs="?", default="config/deploy/demo.deploy",
                    help="deployment file, relative to --root (default: %(default)s)")
    ap.add_argument("--root", default=os.path.normpath(os.path.join(here, "..", "..")),
                    help="the source tree (default: this script's)")
    g = ap.add_mutually_exclusive_group()
    g.add_argument("--check", metavar="FILE", help="exit 1 with a diff when FILE's block differs")
    g.add_argument("--write", metavar="FILE", help="replace FILE's block with the current one")
    a = ap.parse_args(argv)
    try:
        block = render(read_deployment(a.root, a.deployment), a.deployment)
        target = a.check or a.write
        if not target:
            sys.stdout.write(block)
            return 0
        with open(target, encoding="utf-8") as f:
            text = f.read()
        b, e = find_block(text, target)
        if a.write:
            if text[b:e] != block:
                with open(target, "w", encoding="utf-8") as f:
                    f.write(text[:b] + block + text[e:])
            return 0
        if text[b:e] == block:
            print(f"channel_graph: {target}: the channel graph is current ({a.deployment})")
            return 0
        sys.stdout.writelines(difflib.unified_diff(text[b:e].splitlines(True), block.splitlines(True),
                                                   f"{target} (as written)", "generated now"))
        print(f"channel_graph: {target}: the channel graph is out of date; run "
              f"tools/docs/channel_graph.py {a.deployment} --write {target}", file=sys.stderr)
        return 1
    except Error as e:
        print(f"channel_graph: error: {e}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
