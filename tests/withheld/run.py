#!/usr/bin/env python3
"""Run cablab inspect + diagnose on every generated case, one process at a time.
usage: python3 run.py [ID-prefix ...]   -> results/<id>.json, .err, .cmd ; inspect/<file>.json"""
import json, os, subprocess, sys, time, glob, math
import numpy as np
B = os.environ.get("CABLAB", os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "target", "release", "cablab"))
D = os.environ.get("WITHHELD_DIR", os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "target", "withheld"))
os.makedirs(f"{D}/results", exist_ok=True)
os.makedirs(f"{D}/inspect", exist_ok=True)
only = sys.argv[1:]
for tf in sorted(glob.glob(f"{D}/truth/*.json")):
    case = json.load(open(tf))
    cid = case["id"]
    if only and not any(cid.startswith(o) for o in only):
        continue
    if os.path.exists(f"{D}/results/{cid}.json") and not only:
        continue
    kind = case["kind"]
    files = [f["path"] for f in case["files"]]
    # inspect each file
    notes = []
    for f in case["files"]:
        p = subprocess.run([B, "inspect", f["path"], "--json"], capture_output=True, text=True)
        open(f"{D}/inspect/{os.path.basename(f['path'])}.json", "w").write(p.stdout)
        try:
            js = json.loads(p.stdout)
        except Exception:
            notes.append(f"inspect failed: {p.stderr[:300]}")
            continue
        if js.get("kind") != kind:
            notes.append(f"kind read as {js.get('kind')}")
        roles = {c["role"]: c for c in js["channels"] if c["role"] in ("control", "response", "time")}
        if set(roles) != {"control", "response", "time"}:
            notes.append(f"roles {list(roles)}")
        else:
            # compare SI ranges with the truth
            ctrl_max_true = None
            rmax_true = f["response_fullscale_SI"]
            rmax = max(abs(roles["response"]["min"]), abs(roles["response"]["max"]))
            if abs(rmax / rmax_true - 1) > 0.02:
                notes.append(f"response fullscale read {rmax:.4g} SI, truth {rmax_true:.4g}")
        md = js.get("metadata", {})
    single = len(files) == 1
    cmd = [B, "diagnose", *files, "--kind", kind, "--json"]
    if single:
        cmd += ["--length-mm", str(case["files"][0]["L_mm"]), "--diameter-mm", str(case["files"][0]["d_mm"])]
    t0 = time.time()
    try:
        p = subprocess.run(cmd, capture_output=True, text=True, timeout=420)
        rc, out, err = p.returncode, p.stdout, p.stderr
    except subprocess.TimeoutExpired:
        rc, out, err = "timeout", "", "timeout 420 s"
    dt = time.time() - t0
    open(f"{D}/results/{cid}.err", "w").write(err)
    open(f"{D}/results/{cid}.cmd", "w").write(" ".join(cmd) + "\n")
    rec = dict(id=cid, rc=rc, seconds=dt, inspect_notes=notes)
    try:
        rec["out"] = json.loads(out)
    except Exception:
        rec["out"] = None
    json.dump(rec, open(f"{D}/results/{cid}.json", "w"), indent=1)
    v = (rec["out"] or {}).get("verdict", {})
    print(cid, rc, f"{dt:.1f}s", v.get("effect"), v.get("effects"), v.get("equivalent"), notes, flush=True)
