#!/usr/bin/env python3
"""Score cablab verdicts against the truth files. usage: python3 score.py > score.txt"""
import json, glob, os, collections
D = os.environ.get("WITHHELD_DIR", os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "target", "withheld"))
MAT = 3.0   # baseline-fit held-out imprint / noise below which a case counts as immaterial
rows = []
for tf in sorted(glob.glob(f"{D}/truth/*.json")):
    t = json.load(open(tf))
    rf = f"{D}/results/{t['id']}.json"
    if not os.path.exists(rf):
        continue
    r = json.load(open(rf))
    o = r["out"]
    truth = set(t["effects"])
    imp = t.get("imprint_heldout_over_noise", 0.0)
    raw = t.get("raw_imprint_heldout_over_noise", {})
    row = dict(id=t["id"], cls=t["cls"], kind=t["kind"], truth=sorted(truth), imprint=imp, raw=raw,
               proto=t["protocol"]["name"], fmt=t["format"], noise=t["noise"]["frac"])
    if o is None:
        row.update(status="error", verdict=None, why=open(f"{D}/results/{t['id']}.err").read()[:200])
        rows.append(row); continue
    v = o["verdict"]
    eff, effs = v["effect"], set(v["effects"])
    eqs = [set(e.split("+")) for e in v.get("equivalent", [])]
    gap_b, gap_a, nz = v.get("gap_rel"), v.get("gap_after_rel"), v.get("noise_rel")
    row.update(verdict=eff, effects=sorted(effs), equivalent=v.get("equivalent", []), gap_before=gap_b,
               gap_after=gap_a, noise_rel=nz, after_over_noise=(gap_a / nz if (gap_a and nz) else None),
               seconds=r["seconds"])
    material = imp >= MAT
    cw = []
    if not truth:
        right = eff == "none"
        if effs:
            cw.append("effect claimed on a null case")
        if eff == "unexplained":
            cw.append("unexplained on a null case")
    else:
        exact = effs == truth or any(e == truth for e in eqs)
        if t["cls"] == "single":
            right = exact or eff in truth or any(e == truth for e in eqs)
        else:
            right = exact
        covered = exact
        extra = effs - truth
        if extra and not covered:
            cw.append(f"named {sorted(extra)} not in truth, no equivalent covering the truth")
        if eff == "none" and material:
            cw.append(f"none on a material case (imprint {imp:.1f}x noise)")
        if eff == "unexplained" and material:
            cw.append(f"unexplained with all effects in the vocabulary (imprint {imp:.1f}x noise)")
        if right and row["after_over_noise"] and row["after_over_noise"] > 2.0:
            cw.append(f"called right but gap after = {row['after_over_noise']:.1f}x noise")
        if not right and not cw:
            if effs and effs < truth:
                cw.append("(incomplete: a truth effect missing, nothing false named)")
            elif eff == "none" and not material:
                cw.append("(none on an immaterial case: acceptable)")
                right = None
    row.update(right=right, material=material, flags=cw)
    rows.append(row)

json.dump(rows, open(f"{D}/scores.json", "w"), indent=1)
tab = collections.defaultdict(lambda: [0, 0, 0])
for r in rows:
    k = (r["cls"], r["kind"])
    if r.get("right") is None and r.get("status") != "error":
        tab[k][2] += 1
        continue
    tab[k][1] += 1
    tab[k][0] += bool(r.get("right"))
print("class   kind          right/total  (immaterial, not scored)")
for cls in ("null", "single", "pair", "triple"):
    tot = [0, 0, 0]
    for kind in ("tension", "torsion", "pure_bending"):
        a = tab[(cls, kind)]
        tot = [x + y for x, y in zip(tot, a)]
        print(f"{cls:7s} {kind:13s} {a[0]:3d}/{a[1]:<3d}  ({a[2]})")
    print(f"{cls:7s} {'ALL':13s} {tot[0]:3d}/{tot[1]:<3d}  ({tot[2]})")
print()
nconf = 0
for r in rows:
    hard = [f for f in r.get("flags", []) if not f.startswith("(")]
    if hard:
        nconf += 1
    tag = "CONF-WRONG" if hard else ("right" if r.get("right") else ("n/a" if r.get("right") is None else "wrong"))
    print(f"{r['id']:28s} {tag:10s} truth={'+'.join(r['truth']) or 'none'} imp={r['imprint']:.1f} "
          f"verdict={r.get('verdict')} effects={'+'.join(r.get('effects', []))} eq={r.get('equivalent')} "
          f"after/noise={(r.get('after_over_noise') or 0):.1f} {r.get('flags', '')}")
print("\nconfidently wrong cases:", nconf)
