#!/usr/bin/python3
"""The headless 'display' of the simulation configuration ([DISPLAY] DISPLAY in linuxcnc.ini).

linuxcnc starts it once task, motion and HAL are up, and shuts everything down when it exits.
It takes the machine out of E-stop, switches it on, homes all joints (immediate homing), opens
$PL_NGC in auto mode, runs it and polls until the interpreter is idle again, collecting every
message of the error channel. It writes $PL_RESULT (JSON: ok, messages, seconds) and exits
0 when the program ran to its end without an error, 1 otherwise (also after $PL_TIMEOUT s).

$PL_NGC may name several programs separated by ':' (one LinuxCNC start for all of them): each
is run in turn; after an error the program is aborted and the machine brought back (E-stop
reset, machine on, homed, auto mode) before the next. $PL_RESULT then also holds "programs",
per program: ok, messages, run_s, and t_start/t_end (CLOCK_MONOTONIC, the clock of the probe
component's events); $PL_TIMEOUT applies to each program.
"""
import json
import os
import sys
import time

import linuxcnc

KINDS = {linuxcnc.NML_ERROR: "error", linuxcnc.OPERATOR_ERROR: "error", linuxcnc.NML_TEXT: "text",
         linuxcnc.OPERATOR_TEXT: "text", linuxcnc.NML_DISPLAY: "display", linuxcnc.OPERATOR_DISPLAY: "display"}


def main():
    ngcs = os.environ["PL_NGC"].split(":")
    result_path = os.environ.get("PL_RESULT", "result.json")
    timeout = float(os.environ.get("PL_TIMEOUT", "600"))
    s, c, e = linuxcnc.stat(), linuxcnc.command(), linuxcnc.error_channel()
    t_start = time.monotonic()
    messages = []                    # every message, in order
    current = []                     # the messages of the program being run
    result = {"ok": False, "messages": messages, "program": ngcs[0], "programs": []}

    def drain():
        while True:
            m = e.poll()
            if not m:
                return
            msg = {"kind": KINDS.get(m[0], str(m[0])), "text": m[1]}
            messages.append(msg)
            current.append(msg)

    def wait_for(cond, what, limit):
        t_end = time.monotonic() + limit
        while time.monotonic() < t_end:
            s.poll()
            drain()
            if cond():
                return
            if any(m["kind"] == "error" for m in current):
                raise RuntimeError(f"error while waiting for {what}")
            time.sleep(0.02)
        raise RuntimeError(f"timed out after {limit:.0f} s waiting for {what}")

    def ready():
        """E-stop reset, machine on, homed, auto mode (again, after an error)."""
        s.poll()
        if s.task_state != linuxcnc.STATE_ON:
            c.state(linuxcnc.STATE_ESTOP_RESET)
            wait_for(lambda: s.task_state in (linuxcnc.STATE_ESTOP_RESET, linuxcnc.STATE_OFF), "E-stop reset", 10)
            c.state(linuxcnc.STATE_ON)
            wait_for(lambda: s.task_state == linuxcnc.STATE_ON, "machine on", 10)
        if not all(s.homed[j] for j in range(s.joints)):
            c.mode(linuxcnc.MODE_MANUAL)
            c.wait_complete()
            c.home(-1)
            wait_for(lambda: all(s.homed[j] for j in range(s.joints)), "homing", 20)
        c.mode(linuxcnc.MODE_AUTO)
        c.wait_complete()
        wait_for(lambda: s.task_mode == linuxcnc.MODE_AUTO, "auto mode", 10)

    try:
        wait_for(lambda: True, "task", 30)
    except Exception as ex:  # noqa: BLE001
        messages.append({"kind": "error", "text": f"headless_display: {ex}"})
    for ngc in ngcs:
        current.clear()
        run = {"program": ngc, "ok": False, "messages": [], "t_start": time.monotonic()}
        try:
            ready()
            c.program_open(ngc)
            c.wait_complete()
            t_run = time.monotonic()
            run["t_start"] = t_run
            c.auto(linuxcnc.AUTO_RUN, 0)
            wait_for(lambda: s.interp_state != linuxcnc.INTERP_IDLE, "the program to start", 10)
            wait_for(lambda: s.interp_state == linuxcnc.INTERP_IDLE, "the program to end", timeout)
            time.sleep(0.2)
            s.poll()
            drain()
            run["run_s"] = time.monotonic() - t_run
            run["ok"] = not any(m["kind"] == "error" for m in current) and s.task_state == linuxcnc.STATE_ON
            if s.task_state != linuxcnc.STATE_ON:
                current.append({"kind": "error", "text": f"machine not on at the end (task_state {s.task_state})"})
                messages.append(current[-1])
        except Exception as ex:  # noqa: BLE001 - everything goes into the result
            time.sleep(0.2)
            s.poll()
            drain()
            current.append({"kind": "error", "text": f"headless_display: {ex}"})
            messages.append(current[-1])
            try:
                c.abort()
                c.wait_complete()
                wait_for(lambda: s.interp_state == linuxcnc.INTERP_IDLE, "abort", 10)
            except Exception:  # noqa: BLE001
                pass
        run["t_end"] = time.monotonic()
        run["messages"] = list(current)
        result["programs"].append(run)
    if len(result["programs"]) == 1 and "run_s" in result["programs"][0]:
        result["run_s"] = result["programs"][0]["run_s"]
    result["ok"] = bool(result["programs"]) and all(r["ok"] for r in result["programs"])
    try:
        c.state(linuxcnc.STATE_OFF)
    except Exception:  # noqa: BLE001
        pass
    result["seconds"] = time.monotonic() - t_start
    with open(result_path, "w") as f:
        json.dump(result, f, indent=1)
    return 0 if result["ok"] else 1


if __name__ == "__main__":
    sys.exit(main())
