#!/usr/bin/python3
"""The OpenFOAM dictionaries of openfoam_bench.py read by OpenFOAM's own parser (issue 49): each
file the script writes (--write-only, both cases) goes through `foamDictionary FILE -expand`, which
reads it as the solvers do and expands every macro ($p, ...). Checked in the expanded text: every
solver entry of fvSolution names its `solver` (the U.airFinal entry written as `{ $U.air; ... }`
read as the scope U, entry air, and DPMFoam stopped at its first PIMPLE iteration: a dictionary
with that entry is checked too, and must be caught), and the PISO / PIMPLE correctors.

Needs OpenFOAM (Debian: apt-get install openfoam; foamDictionary on PATH, or the bashrc of
$FOAM_BASHRC or /usr/share/openfoam/etc/bashrc): without it the test prints SKIP and exits 77
(CTest: SKIP_RETURN_CODE). CTest openfoam_peer_parser (label unit)."""
import os
import re
import shutil
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
SCRIPT = os.path.join(HERE, "openfoam_bench.py")
FAILS = []


def check(what, ok):
    print(("ok   " if ok else "FAIL ") + what)
    if not ok:
        FAILS.append(what)


def foam_env():
    """The environment in which foamDictionary runs (OpenFOAM's bashrc sourced: its binaries
    need WM_PROJECT_DIR and the etc/ files even when they are on PATH), or None when OpenFOAM is
    not installed."""
    for rc in (os.environ.get("FOAM_BASHRC"), "/usr/share/openfoam/etc/bashrc",
               "/usr/lib/openfoam/openfoam/etc/bashrc"):
        if not rc or not os.path.exists(rc):
            continue
        out = subprocess.run(["bash", "-c", "source %s >/dev/null 2>&1; env -0" % rc],
                             capture_output=True)
        env = dict(kv.split("=", 1) for kv in out.stdout.decode().split("\0") if "=" in kv)
        if shutil.which("foamDictionary", path=env.get("PATH", "")):
            return env
    if shutil.which("foamDictionary") and os.environ.get("WM_PROJECT_DIR"):
        return dict(os.environ)  # an environment set up by the user
    return None


def expand(env, path):
    """foamDictionary's expanded text of `path`, or (None, its message) when it fails."""
    r = subprocess.run(["foamDictionary", path, "-expand"], capture_output=True, text=True,
                       env=env, cwd=os.path.dirname(os.path.dirname(path)), timeout=60)
    if r.returncode != 0 or "FOAM FATAL" in r.stdout + r.stderr:
        return None, (r.stdout + r.stderr).strip()[-600:]
    return r.stdout, ""


def solver_blocks(text):
    """{name: body} of the `solvers { ... }` entries of an expanded fvSolution."""
    m = re.search(r"^solvers\s*\{(.*?)^\}", text, re.M | re.S)
    if not m:
        return {}
    return {name: body for name, body in
            re.findall(r"^\s*(\"[^\"]+\"|[A-Za-z][\w.]*)\s*\{([^{}]*)\}", m.group(1), re.M)}


def check_case(env, what, d):
    files = [os.path.join(r, f) for r, _, fs in os.walk(d) for f in fs]
    check("%s: %d dictionaries written" % (what, len(files)), len(files) >= 6)
    texts = {}
    for f in sorted(files):
        text, why = expand(env, f)
        rel = os.path.relpath(f, d)
        check("%s: foamDictionary reads %s%s" % (what, rel, "" if text else ": " + why),
              text is not None)
        texts[rel] = text or ""
    fv = texts.get(os.path.join("system", "fvSolution"), "")
    blocks = solver_blocks(fv)
    check("%s: fvSolution has solver entries (%s)" % (what, ", ".join(blocks)), len(blocks) >= 2)
    for name, body in blocks.items():
        check("%s: solvers/%s names its solver after expansion" % (what, name),
              re.search(r"\bsolver\s+\w+;", body) is not None)
    return fv


def main():
    env = foam_env()
    if env is None:
        print("SKIP: OpenFOAM is not installed (no foamDictionary; apt-get install openfoam)")
        return 77
    with tempfile.TemporaryDirectory() as tmp:
        for what in ("channel", "fbed"):
            d = os.path.join(tmp, what)
            subprocess.run([sys.executable, SCRIPT, what, "--write-only", "--dict-dir", d],
                           check=True)
            fv = check_case(env, what, d)
            n = re.search(r"\bnCorrectors\s+(\d+);", fv)
            check("%s: 2 correctors after expansion" % what, n is not None and n.group(1) == "2")
            if what == "fbed":
                fin = solver_blocks(fv).get("U.airFinal", "")
                check("fbed: U.airFinal relTol 0 after expansion",
                      re.search(r"\brelTol\s+0;", fin) is not None)
                # the entry as it was before the fix: OpenFOAM's parser must make it fail here
                bad = os.path.join(tmp, "bad")
                shutil.copytree(d, bad)
                path = os.path.join(bad, "system", "fvSolution")
                text = open(path).read()
                text, n = re.subn(r"(\n\s*U\.airFinal\s*\{)[^}]*\}", r"\1 $U.air; relTol 0; }",
                                  text)
                open(path, "w").write(text)
                out, _ = expand(env, path)
                caught = out is None or not re.search(
                    r"\bsolver\s+\w+;", solver_blocks(out).get("U.airFinal", ""))
                check("the old U.airFinal { $U.air; ... } is caught by this check", n == 1 and caught)
    if FAILS:
        print("openfoam_parser: %d check(s) failed" % len(FAILS))
        return 1
    print("openfoam_parser: all checks passed")
    return 0


if __name__ == "__main__":
    sys.exit(main())
