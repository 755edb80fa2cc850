#!/usr/bin/env python3
"""A CLI that never surprises (issue 32, item 4): one test per surprise a new user met.

- one convention: `--json` is a flag printing JSON to stdout (warnings to stderr), HTML is
  `--html FILE`; the old forms (`--json FILE`, `--report`, `--dashboard`) are refused;
- a missing input names what was expected; swapped or wrong-kind inputs are named from
  their content (a manifest given as the log, inputs for errors, a CSV for a model, ...);
- `model add` checks channels and inputs against the model's data before writing, maps
  "EY0C" to the errors' "EY0C_um", and keeps the file's comments; a model naming one
  column twice is refused instead of fitted twice;
- `fit` on a campaign file says which features and cycles it holds (--feature, --cycle);
  a fit whose u rests on too few degrees of freedom, or on residuals at rounding level,
  says so.

Runs the real CLI on a 12-cycle sphere campaign it plans, simulates and evaluates itself.
Env: PROBELOOP (the binary), PROBELOOP_SOURCE_DIR.
"""
import json
import math
import os
import shutil
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from checks import Checks  # noqa: E402

PL = os.environ.get("PROBELOOP", "build/cli/probeloop")
SRC = os.environ.get("PROBELOOP_SOURCE_DIR", ".")
W = tempfile.mkdtemp(prefix="probeloop-surprises-")
check = Checks()


def run(*args, cwd=None):
    p = subprocess.run([PL, *args], capture_output=True, text=True, cwd=cwd)
    return p.returncode, p.stdout, p.stderr


def must(*args, cwd=None):
    rc, out, err = run(*args, cwd=cwd)
    if rc != 0:
        print(f"setup failed: probeloop {' '.join(args)}\n{err}")
        raise SystemExit(1)
    return out


MACHINE = f"{SRC}/parts/machines/nmv5000.yaml"
PART = f"{SRC}/parts/sphere_artifact.yaml"
must("plan", PART, "--machine", MACHINE, "--out", f"{W}/plan")
must("simulate", f"{W}/plan/sphere_cycle.nc", "--machine", MACHINE, "--part", PART,
     "--truth", f"{SRC}/examples/truth_campaign.yaml", "--out", f"{W}/run", "--seed", "1")
must("evaluate", f"{W}/run/points.csv", "--manifest", f"{W}/plan/plan.json", "--out", f"{W}/eval")
PLAN, LOG, POINTS = f"{W}/plan/plan.json", f"{W}/run/dprnt.txt", f"{W}/run/points.csv"
INPUTS, ERRORS = f"{W}/run/inputs.csv", f"{W}/eval/errors.csv"

# --- one convention for --json and --html -------------------------------------------------
MODEL = f"{W}/model.yaml"
MODEL_TEXT = ("# my model: the table-side static map (a comment the user wants kept)\n"
              "kind: error_model\n"
              "data: {inputs: run/inputs.csv, errors: eval/errors.csv}   # relative to this file\n"
              "channels:\n"
              "  EX0C_um:  [{effect: static, input: T_table_C}]   # from the first campaign\n"
              "  EY0C_um:  [{effect: static, input: T_caxis_C}]\n"
              "  EZ0T_um:\n"
              "    - {effect: static, input: T_caxis_C}\n"
              "  ER0T_um:  []\n")
open(MODEL, "w").write(MODEL_TEXT)

json_commands = [
    ("fit", ["fit", "sphere", POINTS, "--feature", "S1", "--cycle", "1"]),
    ("check", ["check", f"{W}/plan/sphere_cycle.nc", "--machine", MACHINE, "--part", PART]),
    ("read", ["read", f"{W}/eval/results.qif"]),
    ("gum", ["gum", f"{SRC}/examples/gum/end_gauge_h1.yaml"]),
    ("model fit", ["model", "fit", MODEL]),
    ("model diagnose", ["model", "diagnose", MODEL]),
    ("model compare", ["model", "compare", MODEL, MODEL]),
]
for name, args in json_commands:
    rc, out, err = run(*args, "--json")
    try:
        doc = json.loads(out)
    except ValueError:
        doc = None
    check(f"{name} --json prints one JSON document on stdout", rc == 0 and isinstance(doc, dict), (err or out)[:300])
    rc_text, text, _ = run(*args)
    check(f"{name} without --json prints text, not JSON", rc_text == 0 and not text.lstrip().startswith("{"), text[:200])
    rc, out, err = run(*args, "--json", f"{W}/out.json")
    check(f"{name}: the old form --json FILE is refused, nothing written",
          rc != 0 and not os.path.exists(f"{W}/out.json"), out[:200] + err[:200])

rc, out, err = run("model", "fit", MODEL, "--json", "--html", f"{W}/fit.html")
ok = rc == 0 and os.path.exists(f"{W}/fit.html")
try:
    json.loads(out)
except ValueError:
    ok = False
check("model fit --json --html: the page is written and stdout stays pure JSON ('Wrote' on stderr)",
      ok and "Wrote" in err, err[:300])
for args in (["model", "fit", MODEL], ["model", "diagnose", MODEL]):
    rc, out, err = run(*args, "--report", f"{W}/r.html")
    check(f"{args[1]}: --report is gone (the HTML option is --html everywhere)", rc != 0 and not os.path.exists(f"{W}/r.html"), err)
rc, out, _ = run("campaign", "run", "--help")
check("campaign run's live page is --html", "--html" in out and "--dashboard" not in out, out[-600:])
for sub in ("ttp", "stepped"):
    rc, out, _ = run("report", sub, "--help")
    check(f"report {sub} writes with --html", rc == 0 and "--html" in out, out[-300:])

# --- a missing input names what was expected ----------------------------------------------
rc, out, err = run("evaluate", f"{W}/nope.txt", "--manifest", PLAN)
check("a missing log: the message names the file and what was expected",
      rc != 0 and "nope.txt" in err and "does not exist" in err and "probe log or CMM export" in err, err)
rc, out, err = run("evaluate", LOG, "--manifest", f"{W}/nope.json")
check("a missing manifest: the message says it is the plan.json of probeloop plan",
      rc != 0 and "nope.json" in err and "plan.json" in err, err)

# --- swapped or wrong-kind inputs, named from their content -------------------------------
wrong = [
    ("log and manifest swapped", ["evaluate", PLAN, "--manifest", LOG, "--out", f"{W}/x"],
     [LOG, "not a plan manifest", "probe log"]),
    ("the errors given as the log", ["evaluate", ERRORS, "--manifest", PLAN, "--out", f"{W}/x"],
     [ERRORS, "errors.csv", "probe log"]),
    ("--inputs and --errors swapped", ["model", "talc", "--inputs", ERRORS, "--errors", INPUTS],
     [ERRORS, "this is an errors.csv", "--inputs expects an inputs.csv"]),
    ("the errors given as a model", ["model", "fit", ERRORS], [ERRORS, "errors.csv", "not a YAML description"]),
    ("a manifest given as a program", ["check", PLAN, "--machine", MACHINE, "--part", PART],
     [PLAN, "JSON document", "not a G-code program"]),
    ("a probe log given to read", ["read", LOG], [LOG, "probe log", "QIF 3.0"]),
    ("the machine given as the piece", ["plan", MACHINE, "--machine", PART, "--out", f"{W}/x"],
     [MACHINE, "'machine' is not a kind of test piece"]),
]
for name, args, needles in wrong:
    rc, out, err = run(*args)
    check(f"{name}: refused with a sentence naming what was given", rc != 0 and all(n in err for n in needles)
          and "invalid literal" not in err and not os.path.exists(f"{W}/x"), err)

# --- model add: checked against the data, comments kept -----------------------------------
rc, out, err = run("model", "add", "lag", "--model", MODEL, "--channels", "EY0C_um", "--input", "T_nope")
check("model add --input T_nope: refused, listing the inputs; the file untouched",
      rc != 0 and "no input 'T_nope'" in err and "T_env_C" in err and open(MODEL).read() == MODEL_TEXT, err)
rc, out, err = run("model", "add", "lag", "--model", MODEL, "--channels", "EY0C_nm")
check("model add --channels EY0C_nm: refused, listing the channels; the file untouched",
      rc != 0 and "no channel 'EY0C_nm'" in err and "EY0C_um" in err and open(MODEL).read() == MODEL_TEXT, err)
rc, out, err = run("model", "add", "lag", "--model", MODEL, "--channels", "EY0C,EZ0T", "--input", "T_env_C")
text = open(MODEL).read()
check("model add --channels EY0C,EZ0T: mapped to EY0C_um and EZ0T_um, said so",
      rc == 0 and "EY0C is EY0C_um" in out and "EY0C:" not in text and "EZ0T:" not in text, out + err)
check("model add keeps the file's comments and layout",
      all(line in text for line in MODEL_TEXT.splitlines() if line.startswith("#") or "# from" in line)
      and "data: {inputs: run/inputs.csv, errors: eval/errors.csv}   # relative to this file" in text, text)
check("model add appends to a flow list and to a block list",
      "EY0C_um:  [{effect: static, input: T_caxis_C}, {effect: lag, input: \"T_env_C\", just_added: true}]" in text
      and "    - {effect: lag, input: \"T_env_C\", just_added: true}" in text, text)
rc, out, err = run("model", "add", "drift", "--model", MODEL, "--channels", "ER0T_um")
text = open(MODEL).read()
check("a second add clears the first's just_added and fills an empty list",
      rc == 0 and text.count("just_added") == 1 and "ER0T_um:  [{effect: drift, just_added: true}]" in text, text)
rc, out, err = run("model", "fit", MODEL, "--json")
fit = json.loads(out) if rc == 0 else {"channels": []}
names = [c["channel"] for c in fit["channels"]]
check("the next fit has each channel once", rc == 0 and sorted(names) == sorted(set(names)) and "EY0C_um" in names, names)
twice = f"{W}/twice.yaml"
open(twice, "w").write("kind: error_model\ndata: {inputs: run/inputs.csv, errors: eval/errors.csv}\n"
                       "channels:\n  EY0C: [{effect: static, input: T_env_C}]\n  EY0C_um: []\n")
rc, out, err = run("model", "fit", twice)
check("a model naming EY0C and EY0C_um is refused, not fitted twice",
      rc != 0 and "'EY0C' and 'EY0C_um' are the same column" in err, err + out[:300])

# --- fit on a campaign file; small nu ---------------------------------------------------------
rc, out, err = run("fit", "sphere", POINTS)
check("fit on a campaign file names its features and cycles and the options that choose",
      rc != 0 and "5 features (S1, S2, S3 ... S5)" in err and "--feature NAME" in err and "12 cycles" in err
      and "--cycle N" in err and "coincide" not in err, err)
rc, out, err = run("fit", "sphere", POINTS, "--feature", "S2")
check("with --feature only: the cycles are named", rc != 0 and "12 cycles (1, 2, 3 ... 12): choose one with --cycle N" in err, err)
rc, out, err = run("fit", "sphere", POINTS, "--feature", "S2", "--cycle", "4")
rows = [l.split(",") for l in open(POINTS) if l.split(",")[1:2] == ["4"] and l.split(",")[3] == "S2"]
check("fit --feature S2 --cycle 4 fits that sphere's points", rc == 0 and f"of {len(rows)} points" in out, out + err)
check("five points, four parameters: the u is flagged (nu = 1, or residuals at rounding level)",
      ("warning: nu = 1" in out or "warning: the residuals are at rounding level" in out) and "--point-u" in out, out)
# Six points on a sphere of radius 10 with a few um of scatter: nu = 6 - 4 = 2.
pts = [(10.003, 0, 0), (-10, 0.002, 0), (0, 10, -0.001), (0, -9.998, 0), (0, 0, 10.002), (0.001, 0, -10)]
open(f"{W}/six.xyz", "w").write("".join(f"{x} {y} {z}\n" for x, y, z in pts))
rc, out, err = run("fit", "sphere", f"{W}/six.xyz")
t2 = 4.303  # Student's t, 95 %, nu = 2 (any table)
check("nu = 2: the warning gives the t factor (4.30 for 95 %) and the way out",
      rc == 0 and "warning: nu = 2" in out and f"t = {t2:.3g}" in out and "--point-u" in out, out)
rc, out, err = run("fit", "sphere", f"{W}/six.xyz", "--json")
doc = json.loads(out) if rc == 0 else {}
check("with --json the warning is in the document and on stderr",
      any("nu = 2" in w for w in doc.get("warnings", [])) and "warning: nu = 2" in err, out[-300:] + err)
rc, out, err = run("fit", "sphere", f"{W}/six.xyz", "--point-u", "1")
check("with --point-u (type B) there is no nu warning", rc == 0 and "warning" not in out, out)
many = [(10 * math.cos(a) * math.cos(b), 10 * math.sin(a) * math.cos(b), 10 * math.sin(b) + 0.001 * ((k * 7) % 5 - 2))
        for k, (a, b) in enumerate((i * 0.7, (i % 5 - 2) * 0.5) for i in range(20))]
open(f"{W}/many.xyz", "w").write("".join(f"{x:.6f} {y:.6f} {z:.6f}\n" for x, y, z in many))
rc, out, err = run("fit", "sphere", f"{W}/many.xyz")
check("20 scattered points (nu = 16): no warning", rc == 0 and "warning" not in out, out)

shutil.rmtree(W, ignore_errors=True)
check.finish()
