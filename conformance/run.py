#!/usr/bin/env python3
# SPDX-License-Identifier: AGPL-3.0-or-later
"""HMC conformance runner: checks any decoder against the vectors.

    run.py --decoder 'CMD {in} {outdir}' [--profile points|full] [--cases DIR]
           [--jobs N] [--timeout S] [--only SUBSTRING]

The decoder command is split like a POSIX shell command line (no shell is
run); `{in}` is replaced by the stream's path and `{outdir}` by a folder,
which does not exist yet, where the decoder must write the canonical dump
(spec/conformance.md). For each case the runner prints one line, PASS,
FAIL or SKIP with the reason, then a summary line; the exit status is 0 iff
no case failed.

Positive cases: the decoder must exit with status 0 and write exactly the
expected files, byte for byte: header.json and level-K.points for every
decoded level and, in the "full" profile, level-K.simplices. Negative cases:
the decoder must exit with a non-zero status (not killed by a signal) and
name the expected error class (spec/hmc.md section 13) somewhere in its
standard error, as a whole word.

Python 3 standard library only.
"""
import argparse
import concurrent.futures
import json
import os
import re
import shlex
import shutil
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
CLASSES = ("bad_magic", "unsupported_version", "truncated", "bad_chunk", "crc_mismatch", "bad_header",
           "bad_huffman_table", "bad_layer", "limit_exceeded")
LEVEL_FILE = re.compile(r"^level-(0|[1-9][0-9]*)\.(points|simplices)$")


def expected_files(case_dir, profile):
    exp = os.path.join(case_dir, "expected")
    names = sorted(os.listdir(exp))
    if profile == "points":
        names = [n for n in names if not n.endswith(".simplices")]
    return exp, names


def first_difference(a, b):
    """Line number (1-based) of the first differing line, for the report."""
    la, lb = a.split(b"\n"), b.split(b"\n")
    for i, (x, y) in enumerate(zip(la, lb)):
        if x != y:
            return "line %d: expected %r, got %r" % (i + 1, x[:60].decode("latin-1"), y[:60].decode("latin-1"))
    return "expected %d lines, got %d" % (len(la) - 1, len(lb) - 1)


def run_case(case_dir, meta, decoder, profile, timeout, work):
    name = meta["name"]
    negative = meta["expect"] == "error"
    if negative and meta["profile"] == "full" and profile == "points":
        return "SKIP", "detecting this error needs reconstruction (full profile)"
    # The stream is copied to a neutral path: a decoder that echoes the path
    # in its message must not name the expected class through the case name.
    slot = os.path.join(work, "case-%d" % meta["_index"])
    os.makedirs(slot)
    outdir = os.path.join(slot, "out")
    stream = os.path.join(slot, "in.hmc")
    shutil.copyfile(os.path.join(case_dir, "stream.hmc"), stream)
    argv = [a.replace("{in}", stream).replace("{outdir}", outdir) for a in shlex.split(decoder)]
    try:
        r = subprocess.run(argv, stdout=subprocess.PIPE, stderr=subprocess.PIPE, timeout=timeout)
    except subprocess.TimeoutExpired:
        return "FAIL", "no answer within %g s" % timeout
    except OSError as e:
        return "FAIL", "cannot run the decoder: %s" % e
    err = r.stderr.decode("utf-8", "replace")
    if r.returncode < 0:
        return "FAIL", "killed by signal %d" % -r.returncode
    if negative:
        cls = meta["error_class"]
        if r.returncode == 0:
            return "FAIL", "decoded without error; expected %s" % cls
        if not re.search(r"(?<![A-Za-z0-9_])%s(?![A-Za-z0-9_])" % cls, err):
            got = [c for c in CLASSES if re.search(r"(?<![A-Za-z0-9_])%s(?![A-Za-z0-9_])" % c, err)]
            return "FAIL", "expected %s, stderr names %s: %s" % (
                cls, ", ".join(got) if got else "no error class", err.strip().splitlines()[-1:] or "")
        return "PASS", cls
    if r.returncode != 0:
        return "FAIL", "exit status %d: %s" % (r.returncode, " ".join(err.strip().splitlines()[-1:]))
    exp, names = expected_files(case_dir, profile)
    if not os.path.isdir(outdir):
        return "FAIL", "no output folder written"
    got = sorted(os.listdir(outdir))
    for n in names:
        if n not in got:
            return "FAIL", "missing %s" % n
        with open(os.path.join(exp, n), "rb") as f:
            want = f.read()
        with open(os.path.join(outdir, n), "rb") as f:
            have = f.read()
        if want != have:
            return "FAIL", "%s differs: %s" % (n, first_difference(want, have))
    extra = [n for n in got if LEVEL_FILE.match(n) and n not in names and not (profile == "points" and n.endswith(".simplices"))]
    if extra:
        return "FAIL", "unexpected output %s" % ", ".join(extra)
    levels = len([n for n in names if n.endswith(".points")])
    return "PASS", "%d level(s)%s" % (levels, ", truncated stream" if meta.get("truncated") else "")


def main():
    ap = argparse.ArgumentParser(description="HMC conformance runner")
    ap.add_argument("--decoder", required=True, help="command line with {in} and {outdir}")
    ap.add_argument("--profile", choices=("points", "full"), default="full")
    ap.add_argument("--cases", default=os.path.join(HERE, "vectors"))
    ap.add_argument("--jobs", type=int, default=os.cpu_count() or 1)
    ap.add_argument("--timeout", type=float, default=120.0, help="seconds per case")
    ap.add_argument("--only", default=None, help="run the cases whose name contains this")
    a = ap.parse_args()
    if "{in}" not in a.decoder or "{outdir}" not in a.decoder:
        ap.error("--decoder must contain {in} and {outdir}")
    cases = []
    for d in sorted(os.listdir(a.cases)):
        p = os.path.join(a.cases, d, "case.json")
        if os.path.isfile(p) and (a.only is None or a.only in d):
            with open(p, encoding="utf-8") as f:
                meta = json.load(f)
            meta["_index"] = len(cases)
            cases.append((os.path.join(a.cases, d), meta))
    if not cases:
        print("no cases in %s" % a.cases)
        return 1
    work = tempfile.mkdtemp(prefix="hmc-conformance-")
    counts = {"PASS": 0, "FAIL": 0, "SKIP": 0}
    try:
        with concurrent.futures.ThreadPoolExecutor(max_workers=max(1, a.jobs)) as pool:
            futures = [pool.submit(run_case, d, m, a.decoder, a.profile, a.timeout, work) for d, m in cases]
            for (d, m), fut in zip(cases, futures):
                try:
                    verdict, why = fut.result()
                except Exception as e:  # a runner bug must not pass silently
                    verdict, why = "FAIL", "runner error: %r" % e
                counts[verdict] += 1
                print("%s %s: %s" % (verdict, m["name"], why), flush=True)
    finally:
        shutil.rmtree(work, ignore_errors=True)
    print("profile %s, %d cases from %s" % (a.profile, len(cases), a.cases))
    print("%d passed, %d failed, %d skipped" % (counts["PASS"], counts["FAIL"], counts["SKIP"]))
    return 0 if counts["FAIL"] == 0 else 1


if __name__ == "__main__":
    sys.exit(main())
