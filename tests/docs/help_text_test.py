#!/usr/bin/env python3
"""Every binary's --help (ctest binaries_help_text): exit status 0, a usage line naming the binary
once, its positional arguments once, and none of the defects glue::Flags used to print:

  usage: launch DEPLOYMENT [NAME=VALUE...] [flags] DEPLOYMENT [NAME=VALUE...]...   (positional twice)
  --set VALUE  ... (repeatable) (repeatable)                                         (marker twice)
  --seed VALUE random seed (default: the config's) (default: -1)                     (a sentinel as default)

and README.md's table of binaries lists each binary of BIN_DIR once (bus-check was listed twice).

  help_text_test.py BIN_DIR [README.md]
"""

import os
import re
import subprocess
import sys


def problems_of(name, text):
    """The defects of one binary's --help text, as messages."""
    found = []
    lines = text.splitlines()
    if not lines or not lines[0].startswith("usage: " + name + " "):
        found.append("the first line is not 'usage: %s ...': %r" % (name, lines[0] if lines else ""))
        return found
    words = lines[0].split()[1:]
    repeated = sorted({w for w in words if words.count(w) > 1})
    if repeated:
        found.append("the usage line repeats %s: %r" % (", ".join(repeated), lines[0]))
    if lines[0].rstrip().endswith("]...") or lines[0].rstrip().endswith("...]..."):
        found.append("the usage line ends in a stray '...': %r" % lines[0])
    for line in lines:
        if line.count("(repeatable)") > 1:
            found.append("'(repeatable)' twice: %r" % line.strip())
        if "(default: -1)" in line or "(default: )" in line or "(default: nan)" in line or "(default: -nan)" in line:
            found.append("a sentinel printed as the default: %r" % line.strip())
        # The help already says what the default is, and the value was appended as well.
        if "(default: " in line and re.sub(r"\(default: [^)]*\)", "", line).count("default") > 0:
            found.append("two defaults: %r" % line.strip())
    return found


def readme_binaries(path):
    """The binaries README.md's "## Binaries" table lists, in order (repeats kept)."""
    names, in_section = [], False
    for line in open(path, encoding="utf-8"):
        if line.startswith("## "):
            in_section = line.strip() == "## Binaries"
        m = re.match(r"^\| `([^`]+)` \|", line)
        if in_section and m:
            names.append(m.group(1))
    return names


def main():
    if len(sys.argv) not in (2, 3):
        sys.exit(__doc__)
    bin_dir = sys.argv[1]
    # The project's binaries; the test executables (NAME_tests, GoogleTest's own --help) are not.
    names = sorted(n for n in os.listdir(bin_dir)
                   if os.path.isfile(os.path.join(bin_dir, n)) and os.access(os.path.join(bin_dir, n), os.X_OK)
                   and not n.endswith("_tests"))
    if len(names) < 10:
        sys.exit("FAIL: only %d binaries in %s (is the build complete?)" % (len(names), bin_dir))
    env = dict(os.environ)
    env.pop("DISPLAY", None)
    failures = 0
    for name in names:
        try:
            run = subprocess.run([os.path.join(bin_dir, name), "--help"], capture_output=True, text=True,
                                 timeout=60, env=env, stdin=subprocess.DEVNULL)
        except subprocess.TimeoutExpired:
            print("FAIL %s: --help did not return within 60 s" % name)
            failures += 1
            continue
        found = problems_of(name, run.stdout)
        if run.returncode != 0:
            found.append("exit status %d (stderr: %s)" % (run.returncode, run.stderr.strip()[:200]))
        for f in found:
            print("FAIL %s: %s" % (name, f))
        failures += bool(found)
        if not found:
            print("ok   %s: %s" % (name, run.stdout.splitlines()[0]))
    # The checks themselves, on the texts that had the defects.
    bad = {
        "launch": "usage: launch DEPLOYMENT [NAME=VALUE...] [flags] DEPLOYMENT [NAME=VALUE...]...\n",
        "eval-slam": "usage: eval-slam [flags]\n  --set VALUE   override KEY=VALUE (repeatable) (repeatable)\n",
        "slam-sim-eval": "usage: slam-sim-eval [flags]\n  --seed VALUE  random seed (default: the config's) (default: -1)\n",
    }
    for name, text in bad.items():
        if not problems_of(name, text):
            print("FAIL the check misses the defect of %r" % text)
            failures += 1
    print("%d of %d binaries with a defective --help" % (failures, len(names)))
    if len(sys.argv) == 3:
        listed = readme_binaries(sys.argv[2])
        for name in sorted({n for n in listed if listed.count(n) > 1}):
            print("FAIL README.md lists %s %d times" % (name, listed.count(name)))
            failures += 1
        for name in names:
            # Test helpers are named with '_' (viewer_png_check); the binaries with '-'.
            if name not in listed and "_" not in name:
                print("FAIL README.md's table of binaries lacks %s" % name)
                failures += 1
        for name in listed:
            if name not in names:
                print("FAIL README.md lists %s, which is not in %s" % (name, bin_dir))
                failures += 1
    sys.exit(1 if failures else 0)


if __name__ == "__main__":
    main()
