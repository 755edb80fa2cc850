"""The pass/fail bookkeeping shared by the Python integration tests."""


class Checks:
    def __init__(self):
        self.passed = 0
        self.failed = 0

    def __call__(self, name, cond, detail=""):
        if cond:
            self.passed += 1
            print("ok   " + name)
        else:
            self.failed += 1
            print("FAIL " + name + ("\n     " + str(detail)[:800] if detail else ""))

    def finish(self):
        print(f"{self.passed} passed, {self.failed} failed")
        raise SystemExit(1 if self.failed else 0)


def run_text_and_json(pl, args, cwd=None):
    """Runs `pl *args`; when args hold `--json PATH`, runs the command twice: once for its
    text (returned) and once with the `--json` flag, whose stdout goes to PATH (the CLI's
    convention: --json prints JSON instead of the text). Returns (returncode, text, stderr)."""
    import subprocess
    args = list(args)
    path = None
    if "--json" in args:
        i = args.index("--json")
        if i + 1 < len(args) and not args[i + 1].startswith("-"):
            path = args.pop(i + 1)
            args.pop(i)
    p = subprocess.run([pl, *args], capture_output=True, text=True, cwd=cwd)
    if path is None or p.returncode != 0:
        return p.returncode, p.stdout, p.stderr
    q = subprocess.run([pl, *args, "--json"], capture_output=True, text=True, cwd=cwd)
    if q.returncode == 0:
        import os
        with open(os.path.join(cwd or ".", path), "w") as f:
            f.write(q.stdout)
    return q.returncode, p.stdout, p.stderr + q.stderr


def cli(pl, workdir):
    """The two ways the integration tests call the CLI at `pl`: run(*args) returns (returncode,
    stdout, stderr); must(*args) returns stdout, or prints the failure, removes `workdir` and
    ends the test with exit 1 when the command fails (a step others depend on)."""
    import shutil
    import subprocess

    def run(*args):
        p = subprocess.run([pl, *args], capture_output=True, text=True)
        return p.returncode, p.stdout, p.stderr

    def must(*args):
        code, out, err = run(*args)
        if code != 0:
            print(f"FAIL probeloop {' '.join(args)}: exit {code}\n{out}\n{err}")
            shutil.rmtree(workdir, ignore_errors=True)
            raise SystemExit(1)
        return out

    return run, must
