"""What the tests on LinuxCNC in simulation share (linuxcnc_sim.py, linuxcnc_safety.py,
linuxcnc_live.py): the skip when LinuxCNC or Debian's Python modules are missing, and the
check that no process of the simulation is left afterwards."""
import os
import shutil
import subprocess
import sys
import time

SRC = os.environ["PROBELOOP_SOURCE_DIR"]
TOOLS = os.path.join(SRC, "tools", "linuxcnc_sim")
SYS_PY = "/usr/bin/python3"
SKIP = 77   # ctest SKIP_RETURN_CODE


def skip_without_linuxcnc(test):
    """Exit 77 (skipped) when LinuxCNC, /usr/bin/python3 with its hal and linuxcnc modules, or
    PyYAML are missing."""
    def skip(why):
        print(f"SKIP {test}: {why}")
        sys.exit(SKIP)
    if not shutil.which("linuxcnc", path="/usr/sbin:/usr/bin:/sbin:/bin"):
        skip("LinuxCNC is not installed (Debian: apt-get install linuxcnc-uspace)")
    if not os.path.exists(SYS_PY) or subprocess.run([SYS_PY, "-c", "import hal, linuxcnc, yaml"],
                                                    capture_output=True).returncode != 0:
        skip("/usr/bin/python3 cannot import hal, linuxcnc and yaml (linuxcnc-uspace, python3-yaml)")


def linuxcnc_processes():
    """Running ones: a zombie waits for its parent (or init) to reap it."""
    ps = subprocess.run(["ps", "-eo", "pid=,stat=,comm="], capture_output=True, text=True).stdout.splitlines()
    return [row.strip() for row in ps if len(row.split()) == 3 and not row.split()[1].startswith("Z")
            and row.split()[2] in ("rtapi_app", "milltask", "linuxcncsvr", "io", "halcmd", "linuxcnc")]


def finish_run(check, work, t0, keep=False):
    """The end of a LinuxCNC test, also when it failed: stops what a killed run left
    (run_program.py --cleanup), checks that no LinuxCNC process remains, prints the wall time,
    and removes the work folder when every check passed (and not `keep`)."""
    subprocess.run([SYS_PY, os.path.join(TOOLS, "run_program.py"), "--cleanup"], timeout=1800)  # waits for a run holding the queue
    t_end = time.monotonic() + 10
    while linuxcnc_processes() and time.monotonic() < t_end:
        time.sleep(0.5)
    left = "\n".join(linuxcnc_processes())
    check("no LinuxCNC process left (rtapi_app, milltask, linuxcncsvr, io, halcmd, linuxcnc)", not left, left)
    print(f"   wall time {time.monotonic() - t0:.0f} s; work folder {work}")
    if not check.failed and not keep:
        shutil.rmtree(work, ignore_errors=True)
