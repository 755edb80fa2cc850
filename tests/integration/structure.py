#!/usr/bin/env python3
"""The project describes itself, and its layering is true (issue 29 item 3):

1. Every folder that holds code has a README.md, and the README names each of the folder's
   own source files (its .cpp, .hpp, .py, .sh files, by file name or by stem: `safety.hpp`,
   `safety`), so that a file added without a word in its folder's README fails here.
2. The libraries are layered as the top CMakeLists.txt lists them (add_subdirectory order,
   docs/architecture.md#layers): an #include "folder/..." in a library's sources names a
   library listed before it, or itself. Unit tests (*_test.cpp, test_support.hpp) may use
   higher layers to check their folder's behaviour; cli/, tests/, fuzz/ and bench/ sit above
   every library.
3. Nothing cites ../shared's DESIGN.md any more: the repository's own docs/architecture.md
   is the design a clone has.

Needs $PROBELOOP_SOURCE_DIR."""
import os, re, subprocess, sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from checks import Checks  # noqa: E402

SRC = os.environ["PROBELOOP_SOURCE_DIR"]
check = Checks()
tracked = subprocess.run(["git", "-C", SRC, "ls-files"], capture_output=True, text=True)
if tracked.returncode == 0 and tracked.stdout.strip():
    files = tracked.stdout.split()
else:  # not a git checkout (a source tarball): every file below the source folder
    files = [os.path.relpath(os.path.join(d, f), SRC) for d, _, fs in os.walk(SRC) for f in fs
             if "/build" not in d and "node_modules" not in d]

# --- 1. READMEs name their folder's files -------------------------------------------------------
CODE = (".cpp", ".hpp", ".py", ".sh")
folders = {}
for f in files:
    d, name = os.path.split(f)
    if not d or d.startswith(("tests/tools", "tests/data", "fuzz/corpus", "fuzz/fixtures", "fuzz/dict")):
        continue
    if name.endswith(CODE):
        folders.setdefault(d, []).append(name)
for d, names in sorted(folders.items()):
    readme = os.path.join(SRC, d, "README.md")
    if not os.path.exists(readme):
        check(f"{d}/ has a README.md", False, f"{len(names)} source files, no README")
        continue
    text = open(readme).read()
    missing = [n for n in sorted(names) if n not in text and os.path.splitext(n)[0] not in text]
    check(f"{d}/README.md names each of its {len(names)} source files", not missing, ", ".join(missing))

# --- 2. includes point down the layers --------------------------------------------------------------
top = open(os.path.join(SRC, "CMakeLists.txt")).read()
order = re.findall(r"^add_subdirectory\((\w+)\)", top, re.M)
libraries = [d for d in order if d not in ("cli", "tests", "fuzz", "bench")]
rank = {d: i for i, d in enumerate(libraries)}
bad = []
for f in files:
    d = f.split("/")[0]
    # Tests sit beside the behaviour they pin and may use higher layers to check it (sim's
    # tests evaluate what the simulator wrote); the libraries themselves may not.
    if d not in rank or not f.endswith((".cpp", ".hpp")) or f.endswith(("_test.cpp", "test_support.hpp")):
        continue
    for n, line in enumerate(open(os.path.join(SRC, f), errors="replace"), 1):
        m = re.match(r'\s*#include "(\w+)/', line)
        if m and m.group(1) in rank and rank[m.group(1)] > rank[d]:
            bad.append(f"{f}:{n} includes {m.group(1)}/ (listed after {d}/)")
check(f"includes point down the layers ({' < '.join(libraries)})", not bad, "\n".join(bad[:20]))

# --- 3. no citation of a design document outside the repository ---------------------------------------
cites = []
for f in files:
    if f.startswith(("tests/integration/structure.py",)) or not os.path.isfile(os.path.join(SRC, f)):
        continue
    if f.endswith((".cpp", ".hpp", ".md", ".txt", ".py", ".sh", ".yaml")):
        for n, line in enumerate(open(os.path.join(SRC, f), errors="replace"), 1):
            if "DESIGN.md" in line:
                cites.append(f"{f}:{n}")
check("no file cites DESIGN.md (docs/architecture.md is the design in the repository)", not cites, ", ".join(cites[:20]))
check("docs/architecture.md exists", os.path.exists(os.path.join(SRC, "docs/architecture.md")), "")
check.finish()
