#!/usr/bin/env python3
"""The README's tutorials run as printed (issue 32, item 2: every command copy-pasteable).

Each ```sh block after a `<!-- tutorial: NAME -->` marker in README.md runs with bash -e,
in a fresh folder holding links to the clone's parts/ and examples/ and with `probeloop` on
PATH, as a user who pasted it would run it. Then:
  - every `tutorial/...` path the README names exists afterwards (the outputs it promises);
  - the model tutorial's `model add` line is the one `model diagnose` printed first after
    "add it:" (the README says it copies the printed command);
  - the reports are pages with the plots they promise (the Chromium checks live with each
    report's own test; here: they exist and are non-trivial HTML).
Env: PROBELOOP (the binary), PROBELOOP_SOURCE_DIR.
"""
import os
import re
import shutil
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from checks import Checks  # noqa: E402

PL = os.path.abspath(os.environ.get("PROBELOOP", "build/cli/probeloop"))
SRC = os.path.abspath(os.environ.get("PROBELOOP_SOURCE_DIR", "."))
W = tempfile.mkdtemp(prefix="probeloop-readme-")
check = Checks()

readme = open(f"{SRC}/README.md").read()
blocks = re.findall(r"<!-- tutorial: (\w+) -->\s*```sh\n(.*?)```", readme, re.S)
check("the README has the five tutorial blocks", [n for n, _ in blocks] == ["sphere", "model", "ttp", "stepped", "rotary"],
      [n for n, _ in blocks])
for d in ("parts", "examples"):
    os.symlink(f"{SRC}/{d}", f"{W}/{d}")
bindir = f"{W}/bin"
os.makedirs(bindir)
os.symlink(PL, f"{bindir}/probeloop")
env = {**os.environ, "PATH": bindir + os.pathsep + os.environ["PATH"]}

outputs = {}
for name, script in blocks:
    p = subprocess.run(["bash", "-euo", "pipefail", "-c", script], cwd=W, env=env, capture_output=True, text=True)
    outputs[name] = p.stdout
    check(f"tutorial '{name}' runs as printed", p.returncode == 0, p.stderr[-1500:])
    if "…" in script or "..." in script.replace("E_X ... E_TTP", ""):
        check(f"tutorial '{name}' has no elided command", False, script)

# The model tutorial copies the first command the diagnosis printed.
model_script = dict(blocks).get("model", "")
added = [l for l in model_script.splitlines() if l.startswith("probeloop model add")]
printed = re.findall(r"^   add it: (.*)$", outputs.get("model", ""), re.M)
check("the model tutorial's `model add` is the diagnosis's first printed command",
      len(added) == 1 and printed and printed[0] == added[0], f"README: {added}\nprinted: {printed[:3]}")

named = sorted(set(re.findall(r"`(tutorial/[^`*\s]+)`", readme)))
check("the README names outputs of the tutorials", len(named) >= 6, named)
for path in named:
    check(f"{path} exists after the tutorials", os.path.exists(f"{W}/{path}"))
for page in ("tutorial/sphere/report.html", "tutorial/ttp/report.html", "tutorial/sw/report.html",
             "tutorial/campaign/fit.html", "tutorial/campaign/diagnosis.html"):
    ok = os.path.exists(f"{W}/{page}")
    text = open(f"{W}/{page}").read() if ok else ""
    check(f"{page} is a page with plots", ok and text.lstrip().startswith("<!DOCTYPE html") and 'class="vega-plot"' in text,
          text[:200])

shutil.rmtree(W, ignore_errors=True)
check.finish()
