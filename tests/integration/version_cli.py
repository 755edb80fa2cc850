#!/usr/bin/env python3
"""`probeloop --version` and the install rule (issue 32, item 1).

- `--version` exits 0 and prints "probeloop <the project's VERSION in CMakeLists.txt> (commit
  <git describe --always --dirty --abbrev=12 of the source tree>)", both read here from the
  sources, not from the binary;
- `cmake --install <build> --prefix <tmp>` puts an executable `bin/probeloop` there that prints
  the same.
Needs $PROBELOOP (in its build folder's cli/) and $PROBELOOP_SOURCE_DIR."""
import os
import re
import shutil
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from checks import Checks  # noqa: E402

PL = os.environ["PROBELOOP"]
SRC = os.environ["PROBELOOP_SOURCE_DIR"]
check = Checks()
version = re.search(r"project\(probeloop VERSION ([0-9.]+)", open(os.path.join(SRC, "CMakeLists.txt")).read()).group(1)
g = subprocess.run(["git", "-C", SRC, "describe", "--always", "--dirty", "--abbrev=12"], capture_output=True, text=True)
commit = g.stdout.strip() if g.returncode == 0 and g.stdout.strip() else "unknown"
want = f"probeloop {version} (commit {commit})"
r = subprocess.run([PL, "--version"], capture_output=True, text=True)
check(f"--version exits 0 and prints '{want}'", r.returncode == 0 and r.stdout.strip() == want,
      f"exit {r.returncode}: {r.stdout!r} {r.stderr!r}")

build = os.path.dirname(os.path.dirname(os.path.abspath(PL)))
prefix = tempfile.mkdtemp(prefix="probeloop-install-")
try:
    i = subprocess.run(["cmake", "--install", build, "--prefix", prefix], capture_output=True, text=True)
    installed = os.path.join(prefix, "bin", "probeloop")
    check("cmake --install puts an executable bin/probeloop under the prefix",
          i.returncode == 0 and os.access(installed, os.X_OK), i.stdout + i.stderr)
    if os.access(installed, os.X_OK):
        r2 = subprocess.run([installed, "--version"], capture_output=True, text=True)
        check("the installed probeloop prints the same version", r2.stdout.strip() == want, r2.stdout)
finally:
    shutil.rmtree(prefix, ignore_errors=True)
check.finish()
