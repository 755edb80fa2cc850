#!/usr/bin/env python3
"""Opens an HTML report in headless Chromium and checks that its Vega plots rendered.

Usage: html_render.py FILE.html N_PLOTS    (exit 0 when every check passes, 1 otherwise)

From another test:
    sys.path.insert(0, "<...>/tests/integration"); from html_render import check
    ok, text = check("report.html", 14)     # text says what was checked and what failed

What "rendered" means (the page contract of report/model_report.hpp):
  - Chromium (Debian `chromium`, or $CHROMIUM) loads the file offline, runs its scripts for
    up to 10 s of virtual time and dumps the resulting DOM;
  - the page has exactly N_PLOTS containers <div class="vega-plot">, each marked
    data-rendered="true" by the page once Vega has run, each holding an <svg class="marks">
    with drawn data marks: elements inside <g class="mark-... role-mark"> groups (paths
    with a non-empty `d`, lines, ...), none of whose path data contains NaN (what Vega draws
    from a value it could not read);
  - the page's error box <div id="vega-errors"> exists and is empty: the page writes every
    script error and every error Vega logs into it.
Plain python3, no third-party modules.
"""
import os
import shutil
import subprocess
import sys
import tempfile
import time
from html.parser import HTMLParser

VIRTUAL_TIME_BUDGET_MS = 10000
TIMEOUT_S = 180
VOID = {"area", "base", "br", "col", "embed", "hr", "img", "input", "link", "meta", "source", "track", "wbr"}


class Node:
    def __init__(self, tag, attrs):
        self.tag = tag
        self.attrs = {k: (v if v is not None else "") for k, v in attrs}
        self.children = []

    def classes(self):
        return self.attrs.get("class", "").split()

    def walk(self):
        yield self
        for c in self.children:
            if isinstance(c, Node):
                yield from c.walk()

    def text(self):
        return "".join(c if isinstance(c, str) else c.text() for c in self.children)


class TreeBuilder(HTMLParser):
    def __init__(self):
        super().__init__(convert_charrefs=True)
        self.root = Node("#document", [])
        self.stack = [self.root]

    def handle_starttag(self, tag, attrs):
        node = Node(tag, attrs)
        self.stack[-1].children.append(node)
        if tag not in VOID:
            self.stack.append(node)

    def handle_startendtag(self, tag, attrs):
        self.stack[-1].children.append(Node(tag, attrs))

    def handle_endtag(self, tag):
        for i in range(len(self.stack) - 1, 0, -1):
            if self.stack[i].tag == tag:
                del self.stack[i:]
                return

    def handle_data(self, data):
        self.stack[-1].children.append(data)


def chromium_binary():
    for name in (os.environ.get("CHROMIUM"), "chromium", "chromium-browser", "google-chrome"):
        if name and shutil.which(name):
            return shutil.which(name)
    return None


def render(path):
    """Returns (dom_text, seconds, stderr) of Chromium's --dump-dom for the file at `path`."""
    binary = chromium_binary()
    if binary is None:
        raise RuntimeError("chromium not found (Debian package `chromium`; scripts/setup.sh installs it)")
    url = "file://" + os.path.abspath(path)
    with tempfile.TemporaryDirectory(prefix="probeloop-chromium-") as profile:
        # --no-sandbox: Chromium refuses to start its sandbox as root (CI containers) and in
        # containers without user namespaces; the page is our own, offline file.
        cmd = [binary, "--headless", "--no-sandbox", "--disable-gpu", "--no-first-run", "--disable-extensions",
               "--user-data-dir=" + profile, f"--virtual-time-budget={VIRTUAL_TIME_BUDGET_MS}", "--dump-dom", url]
        t0 = time.monotonic()
        p = subprocess.run(cmd, capture_output=True, text=True, timeout=TIMEOUT_S)
        seconds = time.monotonic() - t0
    if p.returncode != 0:
        raise RuntimeError(f"chromium exited with {p.returncode}: {p.stderr.strip()[-1500:]}")
    return p.stdout, seconds, p.stderr


def drawn_items(group):
    """Drawn elements of one Vega mark group, and how many of them carry NaN coordinates."""
    drawn, nan = 0, 0
    for n in group.walk():
        if n is group or n.tag == "g":
            continue
        if n.tag == "path":
            d = n.attrs.get("d", "").strip()
            if d:
                drawn += 1
                nan += "NaN" in d
        elif n.tag in ("line", "rect", "circle", "ellipse", "polygon", "polyline", "text", "image"):
            drawn += 1
            nan += any("NaN" in v for v in n.attrs.values())
    return drawn, nan


def check_dom(dom, n_plots):
    """Checks a dumped DOM; returns (ok, lines)."""
    lines, ok = [], True
    tree = TreeBuilder()
    tree.feed(dom)
    tree.close()
    nodes = list(tree.root.walk())

    errors = [n for n in nodes if n.attrs.get("id") == "vega-errors"]
    if len(errors) != 1:
        ok = False
        lines.append(f"FAIL the page has {len(errors)} error boxes <div id=\"vega-errors\">, expected 1")
    elif errors[0].text().strip():
        ok = False
        messages = [c.text().strip() if isinstance(c, Node) else c.strip() for c in errors[0].children]
        lines.append("FAIL errors written into #vega-errors: " + " | ".join(m for m in messages if m)[:1500])
    else:
        lines.append("ok   #vega-errors is empty")

    plots = [n for n in nodes if n.tag == "div" and "vega-plot" in n.classes()]
    if len(plots) != n_plots:
        ok = False
        lines.append(f"FAIL {len(plots)} plot containers <div class=\"vega-plot\">, expected {n_plots}")
    else:
        lines.append(f"ok   {n_plots} plot containers")

    rendered = 0
    for i, div in enumerate(plots):
        name = div.attrs.get("id") or f"plot #{i + 1}"
        problems = []
        if div.attrs.get("data-rendered") != "true":
            problems.append("not marked data-rendered=\"true\" (the Vega view did not finish)")
        svgs = [n for n in div.walk() if n.tag == "svg" and "marks" in n.classes()]
        if len(svgs) != 1:
            problems.append(f"{len(svgs)} <svg class=\"marks\"> elements, expected 1")
            summary = ""
        else:
            svg = svgs[0]
            try:
                w, h = float(svg.attrs.get("width", "0")), float(svg.attrs.get("height", "0"))
            except ValueError:
                w, h = 0.0, 0.0
            if w <= 0 or h <= 0:
                problems.append(f"svg size {w}x{h}")
            counts, total = {}, 0
            for g in svg.walk():
                cls = g.classes()
                if g.tag != "g" or "role-mark" not in cls:
                    continue
                kind = next((c[5:] for c in cls if c.startswith("mark-")), "?")
                drawn, nan = drawn_items(g)
                total += drawn
                counts[kind] = counts.get(kind, 0) + drawn
                if nan:
                    problems.append(f"{nan} {kind} element(s) with NaN coordinates")
            if total == 0:
                problems.append("no drawn data marks in the svg")
            summary = f"svg {w:g}x{h:g}, drawn marks: " + ", ".join(f"{k} {v}" for k, v in sorted(counts.items()))
        if problems:
            ok = False
            lines.append(f"FAIL {name}: " + "; ".join(problems) + (f" ({summary})" if summary else ""))
        else:
            rendered += 1
            lines.append(f"ok   {name}: {summary}")
    lines.append(f"{rendered} of {len(plots)} plots rendered ({n_plots} expected)")
    return ok and rendered == n_plots, lines


def check(path, n_plots):
    """Renders `path` in headless Chromium and checks n_plots Vega plots; returns (ok, text)."""
    if not os.path.isfile(path):
        return False, f"FAIL no such file: {path}"
    try:
        dom, seconds, _ = render(path)
    except (RuntimeError, subprocess.TimeoutExpired) as e:
        return False, f"FAIL rendering {path}: {e}"
    ok, lines = check_dom(dom, n_plots)
    head = f"html_render: {path} ({os.path.getsize(path) / 1e6:.2f} MB) rendered by headless Chromium in {seconds:.1f} s"
    return ok, "\n".join([head] + lines + ["html_render: " + ("OK" if ok else "FAILED")])


def main(argv):
    if len(argv) != 3 or not argv[2].isdigit():
        print("usage: html_render.py FILE.html N_PLOTS", file=sys.stderr)
        return 2
    ok, text = check(argv[1], int(argv[2]))
    try:
        print(text, flush=True)
    except BrokenPipeError:  # piped into head
        pass
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main(sys.argv))
