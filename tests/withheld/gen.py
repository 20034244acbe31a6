#!/usr/bin/env python3
"""Independent truth-model generator for checking `cablab diagnose`.

Sectional 1-D laws driven by a control history (strain / twist per length / curvature).
Truth = elastoplastic baseline (linear isotropic hardening) + zero..three effects:
  kinematic_hardening   Armstrong-Frederick or linear (Prager) back stress
  stiffness_degradation unloading stiffness k(alpha) = k0 (1 - Dmax (1 - exp(-alpha/a_D)))
  viscoelasticity       1-2 Maxwell branches in parallel (driven by total control)
  friction_hysteresis   Iwan model: N Jenkins elements (spring + slider) in parallel
  piecewise_elasticity  bilinear elastic law of the elastic strain (loading = unloading)
  machine_compliance    measured control = specimen control + R / k_machine (machine drives measured)
  sensor_drift          slow linear / exponential drift on the response or control channel

usage: python3 gen.py [--only NAME] [--no-fit]
writes logs/  truth/  (one TOML-ish JSON truth per case) and cases.json
"""
import json, math, os, sys, time
import numpy as np

OUT = os.environ.get("WITHHELD_DIR", os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "target", "withheld"))
LOGS = os.path.join(OUT, "logs")
TRUTH = os.path.join(OUT, "truth")


# ----------------------------------------------------------------------------- the law
class Law:
    """All quantities sectional: x = control strain-like (eps, twist/len, curvature), R = response."""

    def __init__(self, k, Ry, H, kin=None, deg=None, visco=None, fric=None, pw=None):
        self.k, self.Ry, self.H = k, Ry, H
        self.kin = kin      # dict(c=, gamma=)   (gamma=0: linear Prager)
        self.deg = deg      # dict(Dmax=, a=)    a in units of x (plastic strain)
        self.visco = visco  # list of dict(k=, tau=)
        self.fric = fric    # dict(K=, fmin=, fmax=, n=)
        self.pw = pw        # dict(k2=, et=)  threshold on elastic strain; k = k1
        if fric:
            n = fric["n"]
            self.fk = np.full(n, fric["K"] / n)
            # slip forces of the elements spread between fmin and fmax (uniform Iwan density)
            self.ff = np.linspace(fric["fmin"], fric["fmax"], n) / n
        else:
            self.fk = self.ff = None

    def init(self):
        nv = len(self.visco) if self.visco else 0
        nf = len(self.fk) if self.fk is not None else 0
        return (0.0, 0.0, 0.0, np.zeros(nv), np.zeros(nf), 0.0)  # xp, alpha, X, q, s, x_prev

    def sel(self, e):
        if self.pw is None:
            return self.k * e
        et, k2 = self.pw["et"], self.pw["k2"]
        a = abs(e)
        if a <= et:
            return self.k * e
        return math.copysign(self.k * et + k2 * (a - et), e)

    def dfac(self, alpha):
        if self.deg is None:
            return 1.0
        return 1.0 - self.deg["Dmax"] * (1.0 - math.exp(-alpha / self.deg["a"]))

    def backX(self, X, n, dl):
        if self.kin is None:
            return X
        c, g = self.kin["c"], self.kin["gamma"]
        return (X + c * n * dl) / (1.0 + g * dl)

    def step(self, st, x, dt):
        xp, al, X, q, s, x0 = st
        dx = x - x0
        # plastic part (rate independent)
        e = x - xp
        sig = self.dfac(al) * self.sel(e)
        f = abs(sig - X) - (self.Ry + self.H * al)
        if f > 0:
            n = 1.0 if sig - X > 0 else -1.0

            def g(dl):
                ee = e - n * dl
                a2 = al + dl
                return abs(self.dfac(a2) * self.sel(ee) - self.backX(X, n, dl)) - (self.Ry + self.H * a2)
            lo, hi = 0.0, f / (self.k + self.H) * 1.5 + 1e-30
            while g(hi) > 0:
                hi *= 2.0
            for _ in range(60):
                mid = 0.5 * (lo + hi)
                if g(mid) > 0:
                    lo = mid
                else:
                    hi = mid
            dl = 0.5 * (lo + hi)
            xp = xp + n * dl
            X = self.backX(X, n, dl)
            al = al + dl
            sig = self.dfac(al) * self.sel(x - xp)
        R = sig
        if self.visco:
            q = q.copy()
            for i, b in enumerate(self.visco):
                E = math.exp(-dt / b["tau"]) if dt > 0 else 1.0
                rate = dx / dt if dt > 0 else 0.0
                q[i] = q[i] * E + b["k"] * b["tau"] * rate * (1.0 - E) if dt > 0 else q[i] + b["k"] * dx
            R += q.sum()
        if self.fk is not None:
            s = np.clip(s + self.fk * dx, -self.ff, self.ff)
            R += s.sum()
        return R, (xp, al, X, q, s, x)


# ----------------------------------------------------------------------------- driving
def drive(law, segs, fs, km=None, sub=8):
    """segs: list of (mode, target, rate, hold)
       mode 'c' : command = measured control (x + R/km) moves at rate to target
       mode 'cR': command control moves at rate (sign of direction) until R reaches target
       mode 'F' : command = response moves at rate to target (load control)
       hold > 0 : then hold the commanded quantity for `hold` seconds.
    returns t, c_meas (specimen control + R/km), x_spec, R"""
    dt = 1.0 / fs
    h = dt / sub
    st = law.init()
    T, C, Xs, Rs = [0.0], [0.0], [0.0], [0.0]
    t = 0.0
    R = 0.0
    x = 0.0
    cmd_c = 0.0

    def meas(x, R):
        return x + (R / km if km else 0.0)

    def solve(st, target, what):
        nonlocal x
        return solve_x(law, st, target, what, x, h, km)

    need_solve = km is not None
    for mode, target, rate, hold in segs:
        if mode in ("c", "cR"):
            direction = 1.0 if (mode == "cR" and rate > 0) or (mode == "c" and target > cmd_c) else -1.0
            r = abs(rate)
            k = 0
            done = False
            while not done:
                for j in range(sub):
                    cmd_c += direction * r * h
                    if mode == "c" and (cmd_c - target) * direction >= 0:
                        cmd_c = target
                        done = True
                    if need_solve:
                        x = solve(st, cmd_c, "c")
                    else:
                        x = cmd_c
                    R, st = law.step(st, x, h)
                    t += h
                    if mode == "cR" and (R - target) * direction >= 0:
                        done = True
                    if done:
                        break
                T.append(t); C.append(meas(x, R)); Xs.append(x); Rs.append(R)
                k += 1
                if k > 10_000_000:
                    raise RuntimeError("runaway segment")
            cmd_c = meas(x, R)
            hold_mode = "c"
        else:  # load control
            r = abs(rate)
            direction = 1.0 if target > R else -1.0
            cmdF = R
            done = False
            while not done:
                for j in range(sub):
                    cmdF += direction * r * h
                    if (cmdF - target) * direction >= 0:
                        cmdF = target
                        done = True
                    x = solve(st, cmdF, "F")
                    R, st = law.step(st, x, h)
                    t += h
                    if done:
                        break
                T.append(t); C.append(meas(x, R)); Xs.append(x); Rs.append(R)
            cmd_c = meas(x, R)
            hold_mode = "F"
        if hold > 0:
            nh = int(round(hold * fs))
            for i in range(nh):
                for j in range(sub):
                    if hold_mode == "F":
                        x = solve(st, target, "F")
                    elif need_solve:
                        x = solve(st, cmd_c, "c")
                    R, st = law.step(st, x, h)
                    t += h
                T.append(t); C.append(meas(x, R)); Xs.append(x); Rs.append(R)
    return np.array(T), np.array(C), np.array(Xs), np.array(Rs)


def solve_x(law, st, target, what, x0, h, km):
    """x with what(x) == target: 'c' -> x + R(x)/km, 'F' -> R(x); both increasing in x."""
    from scipy.optimize import brentq

    def gfun(xx):
        Rt, _ = law.step(st, xx, h)
        v = xx + (Rt / km if km else 0.0) if what == "c" else Rt
        return v - target
    g0 = gfun(x0)
    if g0 == 0:
        return x0
    d = 1e-7 * (abs(x0) + abs(law.Ry / law.k))
    slope = (gfun(x0 + d) - g0) / d
    if not slope > 0:
        slope = law.k
    step = -g0 / slope
    a, ga = x0, g0
    b = x0 + 1.2 * step
    gb = gfun(b)
    it = 0
    while ga * gb > 0:
        b = x0 + (b - x0) * 2.0
        gb = gfun(b)
        it += 1
        if it > 80:
            raise RuntimeError("no bracket")
    return brentq(gfun, min(a, b), max(a, b), xtol=1e-14 * (abs(x0) + abs(law.Ry / law.k)), rtol=1e-12)


def drive_with_control(law, t, c, km=None, sub=4):
    """Drive a law by a given measured control history (the machine's own record)."""
    st = law.init()
    R = np.zeros_like(c)
    x = 0.0
    for i in range(1, len(t)):
        h = (t[i] - t[i - 1]) / sub
        for j in range(1, sub + 1):
            cc = c[i - 1] + (c[i] - c[i - 1]) * j / sub
            x = solve_x(law, st, cc, "c", x, h, km) if km else cc
            Rv, st = law.step(st, x, h)
        R[i] = Rv
    return R


# ----------------------------------------------------------------------------- protocols
def cycle_count_of(segs):
    return sum(1 for s in segs if s[0] != "hold")


def protocol(kind, name, xa, Ra, rate, ncyc, rng, hold=0.0):
    """xa: amplitude in specimen control (sectional), Ra: a response level for load control.
    Tension: cycles between a small preload and the peak (a cable takes no compression).
    Torsion / pure bending: fully reversed cycles."""
    segs = []
    if kind == "tension":
        fmin = 0.03 * Ra
        if name == "const":
            for i in range(ncyc):
                segs += [("c", xa, rate, hold), ("cR", fmin, -rate, hold)]
        elif name == "steps":
            levels = [0.55, 0.8, 1.0]
            per = max(2, ncyc // len(levels))
            for L in levels:
                for i in range(per):
                    segs += [("c", L * xa, rate, hold), ("cR", fmin, -rate, hold)]
        elif name == "holds":
            for i in range(ncyc):
                segs += [("c", xa, rate, hold), ("cR", fmin, -rate, hold)]
        elif name == "tworate":
            for i in range(ncyc):
                r = rate if i % 2 == 0 else rate * 10
                segs += [("c", xa, r, hold), ("cR", fmin, -r, hold)]
        elif name == "load":
            for i in range(ncyc):
                segs += [("F", Ra, rate, hold), ("F", fmin, rate, hold)]
    else:
        if name in ("const", "holds"):
            for i in range(ncyc):
                segs += [("c", xa, rate, hold), ("c", -xa, rate, hold)]
            segs += [("c", 0.0, rate, 0.0)]
        elif name == "steps":
            levels = [0.5, 0.75, 1.0]
            per = max(2, ncyc // len(levels))
            for L in levels:
                for i in range(per):
                    segs += [("c", L * xa, rate, hold), ("c", -L * xa, rate, hold)]
            segs += [("c", 0.0, rate, 0.0)]
        elif name == "tworate":
            for i in range(ncyc):
                r = rate if i % 2 == 0 else rate * 10
                segs += [("c", xa, r, hold), ("c", -xa, r, hold)]
            segs += [("c", 0.0, rate, 0.0)]
        elif name == "load":
            for i in range(ncyc):
                segs += [("F", Ra, rate, hold), ("F", -Ra, rate, hold)]
            segs += [("F", 0.0, rate, 0.0)]
    return segs


# ----------------------------------------------------------------------------- writers
def fmt(v, nd):
    return f"{v:.{nd}f}"


def write_bluehill(path, meta, t, c, r, kind, cu, ru):
    # Instron Bluehill CSV: "Group : Name,"value",unit" metadata, blank line, names row, units row, quoted cells
    lines = []
    lines.append(f'Results table 1 : Specimen label,"{meta["label"]}"')
    lines.append(f'Method : Test type,"{meta["testtype_en"]}"')
    lines.append(f'Specimen properties : Diameter,"{meta["d_mm"]:.5f}",mm')
    key = "Gauge length" if kind == "tension" else "Length"
    lines.append(f'Specimen properties : {key},"{meta["L_mm"]:.5f}",mm')
    lines.append(f'Test properties : Data rate,"{meta["fs"]:.1f}",Hz')
    lines.append("")
    cn = {"tension": "Extension", "torsion": "Rotation", "pure_bending": "Rotation"}[kind]
    rn = {"tension": "Load", "torsion": "Torque", "pure_bending": "Moment"}[kind]
    lines.append(f"Time,{cn},{rn}")
    lines.append(f"(s),({cu}),({ru})")
    for a, b, cc in zip(t, c, r):
        lines.append(f'"{a:.5f}","{b:.6f}","{cc:.6g}"')
    with open(path, "w", encoding="utf-8", newline="\r\n") as fh:
        fh.write("\n".join(lines) + "\n")


def write_tra(path, meta, t, c, r, kind, cu, ru):
    # ZwickRoell testXpert II ASCII (.TRA), English, Latin-1, comma separated, quoted header
    L = []
    L.append(f'"Customer","cable lab",""')
    L.append(f'"Specimen ID","{meta["label"]}",""')
    L.append(f'"Test type","{meta["testtype_en"]}",""')
    L.append(f'"Diameter",{meta["d_mm"]:g},"mm"')
    if kind == "tension":
        L.append(f'"Gage length, standard travel",{meta["L_mm"]:g},"mm"')
    else:
        L.append(f'"Specimen length",{meta["L_mm"]:g},"mm"')
    L.append(f'"Test speed",{meta["speed"]:g},"{meta["speed_unit"]}"')
    L.append(f'"Date/Clock time",45210.4,""')
    names = {"tension": ('"Time","Standard force","Standard travel"', (ru, cu)),
             "torsion": ('"Time","Torque","Twist angle"', (ru, cu)),
             "pure_bending": ('"Time","Bending moment","Bending angle"', (ru, cu))}[kind]
    L.append(names[0])
    L.append(f'"s","{names[1][0]}","{names[1][1]}"')
    for a, b, cc in zip(t, c, r):
        L.append(f"{a:.4f},{cc:.6g},{b:.6g}")
    with open(path, "w", encoding="latin-1", newline="\n") as fh:
        fh.write("\n".join(L) + "\n")


def write_mts(path, meta, t, c, r, kind, cu, ru):
    # MTS 793 MPT .dat, German locale (decimal comma), Latin-1, tab separated, CRLF
    def de(v, nd):
        return f"{v:.{nd}f}".replace(".", ",")
    L = []
    L.append("MTS793|MPT|DEU|1|2|,|.|:|49|1|1|A")
    L.append("")
    L.append("Bediener Information\t\t\t\t\t\tZeit:\t0\ts\t12.03.2024 09:15:02")
    L.append("Datum : \t12.03.2024")
    L.append("Prüfer : \tLab")
    L.append(f"Probenbezeichnung :  \t{meta['label']}")
    L.append(f"Prüfart :\t{meta['testtype_de']}")
    L.append(f"Durchmesser :\t{de(meta['d_mm'], 2)}")
    L.append(f"Länge :\t{de(meta['L_mm'], 1)}")
    L.append("Bediener Information Ende")
    L.append("")
    L.append(f"Datenerfassung\t\t\t\t\t\tZeit:\t{de(t[-1], 5)}\ts\t12.03.2024 09:15:02")
    cn = {"tension": "Ch 1 Weg", "torsion": "Ch 2 Drehwinkel", "pure_bending": "Ch 2 Biegewinkel"}[kind]
    rn = {"tension": "Ch 1 Kraft", "torsion": "Ch 2 Drehmoment", "pure_bending": "Ch 2 Biegemoment"}[kind]
    L.append(f"Laufzeit\t{rn}\t{cn}")
    L.append(f"s\t{ru}\t{cu}")
    for a, b, cc in zip(t, c, r):
        L.append(f"{de(a, 4)}\t{cc:.6g}\t{de(b, 6)}".replace(".", ","))
    with open(path, "w", encoding="latin-1", newline="\r\n") as fh:
        fh.write("\n".join(L) + "\n")


WRITERS = {"bluehill": (write_bluehill, "csv"), "tra": (write_tra, "TRA"), "mts": (write_mts, "dat")}


# ----------------------------------------------------------------------------- baseline fit (materiality)
def baseline_sim(p, c):
    k, Ry, H = p
    xp = al = 0.0
    out = np.empty_like(c)
    for i, x in enumerate(c):
        s = k * (x - xp)
        f = abs(s) - (Ry + H * al)
        if f > 0:
            dl = f / (k + H)
            n = 1.0 if s > 0 else -1.0
            xp += n * dl
            al += dl
            s = k * (x - xp)
        out[i] = s
    return out


def fit_baseline(recs, p0):
    """recs: list of dict(c=measured control (sectional), r=measured response (noisy), ho=holdout start idx)
    fit (k, Ry, H) jointly on the training part; return params and held-out residuals."""
    from scipy.optimize import least_squares

    def res(q):
        p = np.exp(q)
        out = []
        for rc in recs:
            m = baseline_sim(p, rc["c"])
            out.append((m - rc["r"])[: rc["ho"]] / rc["sd"])
        return np.concatenate(out)
    best = None
    for f in (1.0, 0.7, 1.4):
        q0 = np.log([p0[0], p0[1] * f, max(p0[2], 1e-3 * p0[0]) * f])
        sol = least_squares(res, q0, method="trf", x_scale=1.0, max_nfev=60)
        if best is None or sol.cost < best.cost:
            best = sol
    return np.exp(best.x)


# ----------------------------------------------------------------------------- specimens
# sectional parameters: k (EA [N], GJ [N m^2], EI [N m^2]), Ry (N or N m), H (same units as k)
SPECIMENS = {
    "tension": [
        dict(id="rope8", name="steel wire rope 6x19 IWRC, d 8 mm", d=8.0, L=400.0, k=3.2e6, Ry=14.0e3, H=0.035),
        dict(id="strand3", name="galvanised steel strand 1x7, d 3 mm", d=3.0, L=250.0, k=7.6e5, Ry=5.2e3, H=0.02),
        dict(id="cu4", name="stranded copper conductor 4 mm2, d 2.6 mm", d=2.6, L=200.0, k=3.6e5, Ry=230.0, H=0.012),
    ],
    "torsion": [
        dict(id="strand6", name="steel strand 1x19, d 6 mm", d=6.0, L=200.0, k=3.1, Ry=3.6, H=0.03),
        dict(id="cu4t", name="stranded copper conductor, d 4 mm", d=4.0, L=150.0, k=0.085, Ry=0.055, H=0.02),
    ],
    "pure_bending": [
        dict(id="cable5", name="PVC-sheathed control cable, d 5 mm", d=5.0, L=200.0, k=0.06, Ry=0.045, H=0.03),
        dict(id="cu28", name="copper conductor 7-wire, d 2.8 mm", d=2.8, L=100.0, k=2.2e-3, Ry=2.4e-3, H=0.025),
        dict(id="rope6", name="steel wire rope 7x7, d 6 mm", d=6.0, L=300.0, k=0.35, Ry=0.16, H=0.02),
    ],
}


# ----------------------------------------------------------------------------- case construction
EFF_SHORT = {"kinematic_hardening": "kin", "stiffness_degradation": "deg", "viscoelasticity": "vis",
             "friction_hysteresis": "fric", "piecewise_elasticity": "pw", "machine_compliance": "comp",
             "sensor_drift": "drift"}


def effect_params(eff, sp, kind, rng, scale, Thalf, Ttot, hold):
    k, Ry = sp["k"], sp["Ry"]
    xy = Ry / k
    if eff == "kinematic_hardening":
        if rng.random() < 0.3:
            return dict(model="linear_prager", c=0.06 * k * scale, gamma=0.0)
        Xs = min(0.9, 0.55 * scale) * Ry
        gam = 1.0 / (1.5 * xy)
        return dict(model="armstrong_frederick", c=Xs * gam, gamma=gam, X_sat=Xs)
    if eff == "stiffness_degradation":
        return dict(Dmax=min(0.7, 0.3 * scale), a=2.0 * xy)
    if eff == "viscoelasticity":
        tau = float(np.clip((hold / 3.0) if hold > 0 else rng.uniform(0.2, 0.8) * Thalf, 0.5, 60))
        br = [dict(k=min(0.8, 0.2 * scale) * k, tau=tau)]
        if rng.random() < 0.35:
            br.append(dict(k=min(0.5, 0.1 * scale) * k, tau=tau * 8))
        return dict(branches=br)
    if eff == "friction_hysteresis":
        return dict(K=min(1.5, 0.6 * scale) * k, fmin=0.05 * Ry * scale, fmax=min(0.9, 0.5 * scale) * Ry, n=10)
    if eff == "piecewise_elasticity":
        if kind == "tension":
            return dict(et=0.35 * xy, k2_over_k1=min(3.0, 1.0 + 0.7 * scale))   # constructional stiffening
        return dict(et=0.4 * xy, k2_over_k1=max(0.1, 1.0 - 0.6 * scale))      # Bowden-like softening
    if eff == "machine_compliance":
        return dict(f=min(3.0, 0.8 * scale))   # machine compliance / specimen compliance at the short length
    if eff == "sensor_drift":
        if rng.random() < 0.6:
            return dict(channel="response", shape="linear", total_frac_fs=min(0.3, 0.05 * scale))
        return dict(channel="control", shape="exp", total_frac_amp=min(0.4, 0.06 * scale), tau=Ttot / 3.0)
    raise ValueError(eff)


def build_law(sp, kind, effs, ep, exclude=None):
    k, Ry, H = sp["k"], sp["Ry"], sp["H"] * sp["k"]
    kw = {}
    for e in effs:
        if e == exclude:
            continue
        p = ep[e]
        if e == "kinematic_hardening":
            kw["kin"] = dict(c=p["c"], gamma=p["gamma"])
        elif e == "stiffness_degradation":
            kw["deg"] = dict(Dmax=p["Dmax"], a=p["a"])
        elif e == "viscoelasticity":
            kw["visco"] = p["branches"]
        elif e == "friction_hysteresis":
            kw["fric"] = dict(K=p["K"], fmin=p["fmin"], fmax=p["fmax"], n=p["n"])
        elif e == "piecewise_elasticity":
            kw["pw"] = dict(et=p["et"], k2=p["k2_over_k1"] * k)
    return Law(k, Ry, H, **kw)


def control_factor(kind, L_mm):
    """sectional control -> logged control unit base (mm for tension, deg for angles)"""
    if kind == "tension":
        return L_mm            # strain * L[mm] = mm
    return (L_mm / 1000.0) * 180.0 / math.pi   # (1/m)*(m) rad -> deg


def simulate_record(case, sp, L_mm, rng):
    kind = case["kind"]
    effs, ep = case["effects"], case["effect_params"]
    law = build_law(sp, kind, effs, ep)
    km = None
    if "machine_compliance" in effs:
        # physical machine stiffness fixed from the SHORT length; sectional km = k_phys * L
        kphys = case["k_machine_phys"]
        km = kphys * (L_mm / 1000.0)
    pr = case["protocol"]
    xy = sp["Ry"] / sp["k"]
    xa = pr["amp_xy"] * xy
    Ra = pr.get("load_frac", 1.3) * sp["Ry"]
    rate = xa / pr["Thalf"]
    if pr["name"] == "load":
        rate = Ra / pr["Thalf"]
    segs = protocol(kind, pr["name"], xa, Ra, rate, pr["ncyc"], rng, hold=pr["hold"])
    sub = 3 if (km is not None or pr["name"] == "load") else 6
    t, c, xs, R = drive(law, segs, pr["fs"], km=km, sub=sub)
    # drift (part of the measured truth)
    cm, Rm = c.copy(), R.copy()
    if "sensor_drift" in effs:
        d = ep["sensor_drift"]
        T = t[-1]
        if d["channel"] == "response":
            FS = np.max(np.abs(R))
            Rm = Rm + d["total_frac_fs"] * FS * (t / T)
        else:
            A = np.max(np.abs(c))
            tau = d["tau"]
            cm = cm + d["total_frac_amp"] * A * (1 - np.exp(-t / tau)) / (1 - math.exp(-T / tau))
    return dict(t=t, c=cm, r=Rm, xs=xs, R=R, law=law, km=km, c_clean=c)


def holdout_start(t, c, kind):
    """index where the last cycle starts: last local minimum (tension) / last upward zero crossing
    before the last positive peak (reversed)."""
    n = len(c)
    if kind == "tension":
        # last peak region: find last maximum, then go back to the previous minimum
        pk = n - 1 - int(np.argmax(c[::-1] >= 0.98 * np.max(c[int(0.6 * n):])))
        j = pk
        while j > 0 and c[j - 1] <= c[j] + 1e-15:
            j -= 1
        return j
    # reversed: last cycle = from the last upward crossing of 0 that precedes the last +peak
    pk = n - 1 - int(np.argmax(c[::-1] >= 0.9 * np.max(c)))
    j = pk
    while j > 0 and c[j] > 0:
        j -= 1
    return j


def make_case(case, fit=True, tune=True):
    rng = np.random.default_rng(case["seed"])
    kind = case["kind"]
    sp = next(s for s in SPECIMENS[kind] if s["id"] == case["specimen"])
    pr = case["protocol"]
    lengths = [sp["L"]] if "machine_compliance" not in case["effects"] else [sp["L"], sp["L"] * 2.5]
    scale = case.get("scale", 1.0)
    Ttot_est = pr["ncyc"] * 2 * (pr["Thalf"] + pr["hold"])
    for attempt in range(4 if tune else 1):
        ep = {e: effect_params(e, sp, kind, np.random.default_rng(case["seed"] + 7), scale, pr["Thalf"],
                               Ttot_est, pr["hold"]) for e in case["effects"]}
        case["effect_params"] = ep
        case["scale"] = scale
        if "machine_compliance" in ep:
            kspec_short = sp["k"] / (sp["L"] / 1000.0)      # physical stiffness at the short length
            case["k_machine_phys"] = kspec_short / ep["machine_compliance"]["f"]
        recs = []
        for L in lengths:
            r = simulate_record(case, sp, L, np.random.default_rng(case["seed"] + 11))
            r["L"] = L
            r["ho"] = holdout_start(r["t"], r["c"], kind)
            FS = float(np.max(np.abs(r["r"])))
            r["sd"] = case["noise"]["frac"] * FS
            nrng = np.random.default_rng(case["seed"] + int(L))
            noise = nrng.normal(0, r["sd"], len(r["t"]))
            if case["noise"].get("hum"):
                noise += r["sd"] * 1.0 * np.sin(2 * np.pi * 50.0 * r["t"] + nrng.uniform(0, 6.28))
            rn = r["r"] + noise
            if case["noise"].get("quant"):
                q = 1.5 * r["sd"]
                rn = np.round(rn / q) * q
            r["rn"] = rn
            # effective noise sd actually added
            r["sd_eff"] = float(np.std(rn - r["r"]))
            recs.append(r)
        if not fit:
            break
        p = fit_baseline([dict(c=r["c"], r=r["rn"], ho=r["ho"], sd=r["sd_eff"]) for r in recs],
                         (sp["k"], sp["Ry"], sp["H"] * sp["k"]))
        imps = []
        for r in recs:
            m = baseline_sim(p, r["c"])
            ho = slice(r["ho"], None)
            imps.append(float(np.sqrt(np.mean((m[ho] - r["r"][ho]) ** 2)) / r["sd_eff"]))
        imprint = float(np.sqrt(np.mean(np.square(imps))))
        case["baseline_fit_params_mine"] = [float(v) for v in p]
        case["imprint_heldout_over_noise"] = imprint
        if not case["effects"] or imprint >= 5.0 or not tune:
            break
        scale *= 1.7
    # per effect raw imprint: law without the effect, driven by the clean measured control
    if case["effects"] and fit:
        per = {}
        r = recs[0]
        for e in case["effects"]:
            lw = build_law(sp, kind, case["effects"], case["effect_params"], exclude=e)
            km = r["km"] if (e != "machine_compliance") else None
            cdrv = r["c"]
            d = case["effect_params"].get("sensor_drift")
            if d and e != "sensor_drift" and d["channel"] == "control":
                cdrv = r["c_clean"]   # the other effects' imprint, seen without the drift
            Rred = drive_with_control(lw, r["t"], cdrv, km=km, sub=3)
            if d and e != "sensor_drift" and d["channel"] == "response":
                Rred = Rred + (r["r"] - r["R"])
            ho = slice(r["ho"], None)
            per[e] = float(np.sqrt(np.mean((Rred[ho] - r["r"][ho]) ** 2)) / r["sd_eff"])
        case["raw_imprint_heldout_over_noise"] = per
    return case, recs, sp


def write_case(case, recs, sp):
    kind = case["kind"]
    fmt_name = case["format"]
    wr, ext = WRITERS[fmt_name]
    files = []
    for i, r in enumerate(recs):
        L = r["L"]
        cf = control_factor(kind, L)
        if kind == "tension":
            cu = "mm"
            big = np.max(np.abs(r["rn"])) > 5000
            ru, rf = ("kN", 1e-3) if big else ("N", 1.0)
        else:
            cu = "deg" if fmt_name == "bluehill" else "°"
            small = np.max(np.abs(r["rn"])) < 0.5
            if small:
                ru, rf = ("N.mm" if fmt_name == "bluehill" else "Nmm"), 1e3
            else:
                ru, rf = ("N·m" if fmt_name != "mts" else "N·m"), 1.0
        tt = {"tension": ("Tension", "Zugversuch"), "torsion": ("Torsion", "Torsionsversuch"),
              "pure_bending": ("Pure bending", "Reine Biegung")}[kind]
        meta = dict(label=f"{case['id']}-{i+1}", d_mm=sp["d"], L_mm=L, fs=case["protocol"]["fs"],
                    testtype_en=tt[0], testtype_de=tt[1], speed=1.0, speed_unit="mm/min")
        suffix = "" if len(recs) == 1 else f"_L{int(round(L))}"
        path = os.path.join(LOGS, f"{case['id']}{suffix}.{ext}")
        wr(path, meta, r["t"], r["c"] * cf, r["rn"] * rf, kind, cu, ru)
        files.append(dict(path=path, L_mm=L, d_mm=sp["d"], control_unit=cu, response_unit=ru,
                          response_factor_to_file=rf, control_factor_to_file=cf, rows=len(r["t"]),
                          holdout_start_row=int(r["ho"]), noise_sd_SI=r["sd_eff"],
                          fs_Hz=case["protocol"]["fs"], duration_s=float(r["t"][-1]),
                          response_fullscale_SI=float(np.max(np.abs(r["rn"])))))
    case["files"] = files
    return files


# ----------------------------------------------------------------------------- the plan
EFFS = ["kinematic_hardening", "stiffness_degradation", "viscoelasticity", "friction_hysteresis",
        "piecewise_elasticity", "machine_compliance", "sensor_drift"]
FORMATS = ["bluehill", "tra", "mts"]


def make_plan():
    rng = np.random.default_rng(20240519)
    plan = []
    kinds = ["tension", "torsion", "pure_bending"]

    def proto_for(effs, kind, i):
        names = ["const", "steps", "holds", "tworate"] + (["load"] if kind != "pure_bending" else [])
        name = names[i % len(names)]
        if "viscoelasticity" in effs and rng.random() < 0.6:
            name = ["holds", "tworate"][i % 2]
        if name == "load" and ({"stiffness_degradation", "machine_compliance"} & set(effs)):
            name = "const"
        ncyc = int(rng.choice([3, 4, 5, 6, 8, 10, 12, 16, 20]))
        if name == "steps":
            ncyc = max(ncyc, 6)
        Thalf = float(rng.choice([4.0, 6.0, 10.0, 15.0, 25.0]))
        hold = float(rng.choice([5.0, 10.0, 20.0, 30.0])) if name == "holds" else 0.0
        ttot = ncyc * 2 * (Thalf + hold) * (1.6 if name == "tworate" else 1.0)
        fs = float(rng.choice([10, 20, 25, 50, 100, 200]))
        fs = float(max(10.0, min(fs, 12000.0 / ttot)))
        fs = float(round(fs))
        amp = float(rng.uniform(1.6, 3.2))
        return dict(name=name, ncyc=ncyc, Thalf=Thalf, hold=hold, fs=fs, amp_xy=amp, load_frac=float(rng.uniform(0.75, 1.08)))

    def noise():
        frac = float(np.exp(rng.uniform(np.log(0.001), np.log(0.01))))
        u = rng.random()
        return dict(frac=frac, quant=bool(u < 0.2), hum=bool(0.2 <= u < 0.35))

    idx = [0]

    def add(kind, effs):
        i = idx[0]
        idx[0] += 1
        sp = SPECIMENS[kind][i % len(SPECIMENS[kind])]
        cls = {0: "null", 1: "single", 2: "pair", 3: "triple"}[len(effs)]
        tag = "null" if not effs else "+".join(EFF_SHORT[e] for e in effs)
        cid = f"c{i:03d}_{kind[:4]}_{tag}"
        plan.append(dict(id=cid, cls=cls, kind=kind, specimen=sp["id"], effects=list(effs),
                         protocol=proto_for(effs, kind, i), noise=noise(), format=FORMATS[i % 3],
                         seed=int(1000 + 17 * i)))

    # nulls
    for kind, n in (("tension", 4), ("torsion", 3), ("pure_bending", 3)):
        for _ in range(n):
            add(kind, [])
    # singles: every effect on every kind, plus repeats of the cable-typical ones
    for kind in kinds:
        for e in EFFS:
            add(kind, [e])
    for kind in kinds:
        for e in ["friction_hysteresis", "viscoelasticity", "kinematic_hardening", "sensor_drift"]:
            add(kind, [e])
    # pairs
    import itertools
    pairs = list(itertools.combinations(EFFS, 2))   # 21
    for j, (a, b) in enumerate(pairs):
        add(kinds[j % 3], [a, b])
    for j, (a, b) in enumerate(pairs):
        if j % 2 == 0:
            add(kinds[(j + 1) % 3], [a, b])
    # triples
    trip = [("friction_hysteresis", "viscoelasticity", "kinematic_hardening"),
            ("friction_hysteresis", "stiffness_degradation", "sensor_drift"),
            ("viscoelasticity", "kinematic_hardening", "machine_compliance"),
            ("piecewise_elasticity", "friction_hysteresis", "viscoelasticity"),
            ("kinematic_hardening", "stiffness_degradation", "viscoelasticity"),
            ("friction_hysteresis", "sensor_drift", "machine_compliance")]
    for j, t in enumerate(trip):
        add(kinds[j % 3], list(t))
    # extra pairs of the cable-typical effects (added after the first run; ids c081..)
    extra = [("tension", "friction_hysteresis", "viscoelasticity"), ("pure_bending", "friction_hysteresis", "viscoelasticity"),
             ("torsion", "kinematic_hardening", "friction_hysteresis"), ("pure_bending", "kinematic_hardening", "friction_hysteresis"),
             ("tension", "stiffness_degradation", "friction_hysteresis"), ("pure_bending", "kinematic_hardening", "viscoelasticity"),
             ("tension", "stiffness_degradation", "viscoelasticity"), ("torsion", "friction_hysteresis", "sensor_drift")]
    for kind, a, b in extra:
        add(kind, [a, b])
    return plan


def main():
    os.makedirs(LOGS, exist_ok=True)
    os.makedirs(TRUTH, exist_ok=True)
    only = None
    fit = "--no-fit" not in sys.argv
    if "--only" in sys.argv:
        only = sys.argv[sys.argv.index("--only") + 1].split(",")
    plan = make_plan()
    if "--list" in sys.argv:
        for c in plan:
            print(c["id"], c["protocol"]["name"], c["format"])
        return
    for case in plan:
        if only and not any(case["id"].startswith(o) for o in only):
            continue
        t0 = time.time()
        case, recs, sp = make_case(case, fit=fit)
        write_case(case, recs, sp)
        case["specimen_desc"] = sp
        case["gen_seconds"] = time.time() - t0

        def clean(o):
            if isinstance(o, dict):
                return {k: clean(v) for k, v in o.items()}
            if isinstance(o, (list, tuple)):
                return [clean(v) for v in o]
            if isinstance(o, (np.floating,)):
                return float(o)
            if isinstance(o, (np.integer,)):
                return int(o)
            return o
        with open(os.path.join(TRUTH, case["id"] + ".json"), "w") as fh:
            json.dump(clean(case), fh, indent=1)
        print(case["id"], f"rows={[f['rows'] for f in case['files']]}",
              f"imprint={case.get('imprint_heldout_over_noise', 0):.1f}",
              {k: round(v, 1) for k, v in case.get("raw_imprint_heldout_over_noise", {}).items()},
              f"scale={case['scale']:.2f}", f"{case['gen_seconds']:.1f}s", flush=True)


if __name__ == "__main__":
    main()
