#!/usr/bin/python3
"""Run one G-code program on LinuxCNC in simulation, headless, and stop it cleanly.

Usage: run_program.py RUN_DIR PROGRAM.ngc [PROGRAM2.ngc ...] [--timeout 300] [--user plsim]
       run_program.py --cleanup   (stop what a killed run left: the user's processes, realtime)

RUN_DIR holds a configuration written by make_config.py (linuxcnc.ini, sim.hal, tool.tbl). The
program is copied into RUN_DIR, which is LinuxCNC's working folder: (LOGOPEN,name) writes
RUN_DIR/name. LinuxCNC refuses to run as root: as root this runs it as --user (created with
useradd if missing, RUN_DIR handed to it); as anyone else, as that user. The display is
headless_display.py (it runs the program and exits; linuxcnc then shuts down). Whatever happens
(error, timeout, Ctrl-C), the process group is stopped (SIGTERM: linuxcnc's own cleanup, then
SIGKILL), realtime is unloaded, and no process of the user may remain (rtapi_app, milltask,
linuxcncsvr, io, halcmd, the components): it says so and fails otherwise.
Exit status: 0 if the program ran to its end without an error message, 1 otherwise.
Writes RUN_DIR/result.json (the display's messages) and RUN_DIR/linuxcnc.out (its output).
"""
import argparse
import fcntl
import json
import os
import pwd
import shutil
import signal
import subprocess
import sys
import time

PATH = "/usr/sbin:/usr/bin:/sbin:/bin"   # the system python3 (hal, linuxcnc), not a pyenv one


def linuxcnc_available():
    return shutil.which("linuxcnc", path=PATH) is not None and os.path.exists("/usr/bin/python3")


def ensure_user(user):
    try:
        return pwd.getpwnam(user)
    except KeyError:
        if os.geteuid() != 0:
            raise SystemExit(f"run_program: user {user} does not exist and only root can create it")
        subprocess.run(["useradd", "-m", user], check=True)
        return pwd.getpwnam(user)


LINUXCNC_NAMES = {"rtapi_app", "milltask", "linuxcncsvr", "io", "halcmd", "linuxcnc"}


def user_pids(uid):
    """The processes of the simulation: as root, every process with the user's uid as its real,
    effective or saved uid (it runs nothing else; rtapi_app is setuid root and keeps the user
    only as its saved uid); otherwise, this user's LinuxCNC processes (rtapi_app, milltask,
    linuxcncsvr, io, halcmd, linuxcnc, the display and the probe component)."""
    pids = []
    for d in os.listdir("/proc"):
        if not d.isdigit() or int(d) == os.getpid():
            continue
        try:
            with open(f"/proc/{d}/status") as f:
                status = dict(line.split(":", 1) for line in f if ":" in line)
            with open(f"/proc/{d}/cmdline", "rb") as f:
                cmd = f.read().replace(b"\0", b" ").decode(errors="replace")
        except OSError:
            continue
        if status.get("State", "").strip().startswith("Z"):
            continue
        uids = {int(u) for u in status.get("Uid", "").split()[:3]}
        if uid not in uids:
            continue
        name = status.get("Name", "").strip()
        if os.geteuid() == 0 or name in LINUXCNC_NAMES or "sphere_probe.py" in cmd or "headless_display.py" in cmd:
            pids.append(int(d))
    return sorted(pids)


def describe(pids):
    rows = []
    for p in pids:
        try:
            with open(f"/proc/{p}/cmdline", "rb") as f:
                rows.append(f"{p} " + f.read().replace(b"\0", b" ").decode(errors="replace")[:120])
        except OSError:
            pass
    return rows


def as_user(user, argv):
    if os.geteuid() == 0:
        return ["runuser", "-u", user, "--"] + argv
    return argv


def stop_everything(proc, user, uid, run_dir, log):
    """SIGTERM to the group (linuxcnc traps it and cleans up), then SIGKILL; unload realtime."""
    if proc is not None and proc.poll() is None:
        try:
            os.killpg(proc.pid, signal.SIGTERM)
        except ProcessLookupError:
            pass
        try:
            proc.wait(timeout=40)
        except subprocess.TimeoutExpired:
            try:
                os.killpg(proc.pid, signal.SIGKILL)
            except ProcessLookupError:
                pass
            proc.wait(timeout=10)
    elif proc is None:   # --cleanup: the linuxcnc scripts of a killed run do their own cleanup first
        scripts = [p for p in user_pids(uid) if any(" /usr/bin/linuxcnc " in row + " " for row in describe([p]))]
        for p in scripts:   # its whole group: bash runs the trap only once the display has exited
            try:
                os.killpg(os.getpgid(p), signal.SIGTERM)
            except ProcessLookupError:
                pass
        t_end = time.monotonic() + 40
        while time.monotonic() < t_end and any(os.path.exists(f"/proc/{p}") for p in scripts):
            time.sleep(0.2)
    # linuxcnc's cleanup has asked rtapi_app (its own session, setuid root) to exit: give it time
    t_end = time.monotonic() + 10
    while user_pids(uid) and time.monotonic() < t_end:
        time.sleep(0.2)
    # anything left: let halrun unload it, then kill by id
    if user_pids(uid):
        subprocess.run(as_user(user, ["env", f"PATH={PATH}", "halrun", "-U"]), cwd=run_dir,
                       stdout=log, stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL, timeout=30)
        t_end = time.monotonic() + 5
        while user_pids(uid) and time.monotonic() < t_end:
            time.sleep(0.2)
    left, t_end = [], time.monotonic() + 10
    while time.monotonic() < t_end:
        now = user_pids(uid)
        if not now:
            break
        left += [p for p in now if p not in left]
        for p in now:
            try:
                os.kill(p, signal.SIGKILL)
            except (ProcessLookupError, PermissionError):
                pass
        time.sleep(0.3)
    if os.geteuid() == 0 and not user_pids(uid):   # NML segments a killed linuxcnc left (stale serial numbers)
        for line in subprocess.run(["ipcs", "-m"], capture_output=True, text=True).stdout.splitlines():
            f = line.split()
            if len(f) >= 6 and f[2] == user and f[5] == "0":
                subprocess.run(["ipcrm", "-m", f[1]], capture_output=True)
    lock = "/tmp/linuxcnc.lock"
    if os.path.exists(lock) and not user_pids(uid):
        try:
            os.remove(lock)
        except OSError:
            pass
    return left


QUEUE_LOCK = "/tmp/probeloop-linuxcnc.flock"


def run(run_dir, program, timeout=300.0, user="plsim", quiet=False):
    """Returns (ok, result dict). Raises RuntimeError if processes were left behind.
    program: one path, or a list of them, run in turn in one LinuxCNC session (result["programs"]
    per program; timeout per program; ok = every one ran to its end without an error).
    Only one LinuxCNC can run on a machine: a second caller waits for the first (an exclusive
    flock on QUEUE_LOCK, released when the run ends or its process dies)."""
    with open(QUEUE_LOCK, "a") as queue:
        try:
            os.chmod(QUEUE_LOCK, 0o666)
        except PermissionError:
            pass
        fcntl.flock(queue, fcntl.LOCK_EX)
        return _run_locked(run_dir, program, timeout, user, quiet)


def _run_locked(run_dir, program, timeout, user, quiet):
    run_dir = os.path.abspath(run_dir)
    pw = ensure_user(user) if os.geteuid() == 0 else pwd.getpwuid(os.geteuid())
    user, uid = pw.pw_name, pw.pw_uid
    stale = user_pids(uid)
    if stale:
        raise RuntimeError("processes of the simulation user are still running (a previous run?):\n  "
                           + "\n  ".join(describe(stale)))
    if os.path.exists("/tmp/linuxcnc.lock"):
        others = subprocess.run(["pgrep", "-x", "linuxcncsvr"], capture_output=True, text=True).stdout.split()
        if others:
            raise RuntimeError("another LinuxCNC is running on this machine (linuxcncsvr " + " ".join(others) + ")")
        os.remove("/tmp/linuxcnc.lock")   # stale: linuxcnc would ask on stdin whether to restart
    programs = [program] if isinstance(program, str) else list(program)
    ngcs = []
    for prog in programs:   # several: one LinuxCNC start, run in turn (headless_display.py)
        ngc = os.path.join(run_dir, os.path.basename(prog))
        if ":" in ngc or ngc in ngcs:
            raise ValueError(f"run_program: program names must be distinct and without ':' ({ngc})")
        if os.path.abspath(prog) != ngc:
            shutil.copyfile(prog, ngc)
        ngcs.append(ngc)
    result_path = os.path.join(run_dir, "result.json")
    if os.path.exists(result_path):
        os.remove(result_path)
    if os.geteuid() == 0:
        for root, dirs, files in os.walk(run_dir):
            for n in [root] + [os.path.join(root, f) for f in files]:
                os.chown(n, uid, pw.pw_gid)
    env = ["env", f"PATH={PATH}", f"HOME={pw.pw_dir}", f"PL_NGC={':'.join(ngcs)}", f"PL_RESULT={result_path}",
           f"PL_TIMEOUT={timeout}"]
    log_path = os.path.join(run_dir, "linuxcnc.out")
    proc = None
    ok, result, left = False, {"ok": False, "messages": []}, []
    with open(log_path, "w") as log:
        try:
            proc = subprocess.Popen(as_user(user, env + ["linuxcnc", os.path.join(run_dir, "linuxcnc.ini")]),
                                    cwd=run_dir, stdout=log, stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL,
                                    start_new_session=True)
            try:
                rc = proc.wait(timeout=timeout * len(ngcs) + 60)
            except subprocess.TimeoutExpired:
                rc = None
                result["messages"].append({"kind": "error",
                                           "text": f"run_program: timed out after {timeout * len(ngcs) + 60:.0f} s"})
            if os.path.exists(result_path):
                with open(result_path) as f:
                    result = json.load(f)
            elif rc is not None:
                result["messages"].append({"kind": "error", "text": f"linuxcnc exited ({rc}) before the display ran; see {log_path}"})
            ok = rc == 0 and result.get("ok", False)
        finally:
            left = stop_everything(proc, user, uid, run_dir, log)
    if not ok and not quiet:
        pf = os.path.join(pw.pw_dir, "linuxcnc_print.txt")
        if os.path.exists(pf):
            with open(pf, errors="replace") as f:
                tail = f.read().splitlines()[-15:]
            print("  (last lines of " + pf + ")\n    " + "\n    ".join(tail))
    if not quiet:
        for m in result.get("messages", []):
            print(f"  linuxcnc {m['kind']}: {m['text']}")
    if left:
        raise RuntimeError("processes left after the run, killed:\n  " + "\n  ".join(describe(left) or map(str, left)))
    return ok, result


def main():
    ap = argparse.ArgumentParser(description="Run a G-code program on LinuxCNC in simulation, headless.")
    ap.add_argument("run_dir", nargs="?")
    ap.add_argument("program", nargs="*", help="one or more programs, run in turn in one LinuxCNC session")
    ap.add_argument("--cleanup", action="store_true", help="only stop what a killed run left behind")
    ap.add_argument("--timeout", type=float, default=300.0)
    ap.add_argument("--user", default="plsim")
    a = ap.parse_args()
    if a.cleanup:
        try:
            pw = pwd.getpwnam(a.user) if os.geteuid() == 0 else pwd.getpwuid(os.geteuid())
        except KeyError:
            return 0   # the user was never created: nothing ran
        # after the run holding the queue, if any: what it runs is not left over
        with open(QUEUE_LOCK, "a") as queue, open(os.devnull, "w") as log:
            fcntl.flock(queue, fcntl.LOCK_EX)
            left = stop_everything(None, pw.pw_name, pw.pw_uid, "/tmp", log)
        if left:
            print("run_program: stopped what a previous run left: " + " ".join(map(str, left)))
        return 0
    if not a.run_dir or not a.program:
        ap.error("RUN_DIR and PROGRAM are required")
    ok, result = run(a.run_dir, a.program, a.timeout, a.user)
    for r in result.get("programs", []):
        print(("ran" if r["ok"] else "FAILED") + f": {os.path.basename(r['program'])} on LinuxCNC"
              f" ({r.get('run_s', 0):.1f} s of program)")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
