# %% [markdown]
# # aeroident from Python: a quick start
#
# Notebook-style (cells separated by `# %%`; runs as a plain script too):
#
#     python -m venv .venv && .venv/bin/pip install "./crates/python[ray]"
#     .venv/bin/python examples/python_quickstart.py
#
# Uses the HFB-320 flight record in ../shared (Jategaonkar 2015) when it is there, and the
# F-16 model and a synthetic record otherwise. Everything runs in the Rust library: the same
# numbers as the `aeroident` command line.

# %%
from pathlib import Path

import numpy as np

import aeroident

ROOT = Path(__file__).resolve().parents[1]
HFB = ROOT.parent / "shared/flightdata/jategaonkar_hfb320_attas/csv/hfb320_1_10.csv"
MAPPING = ROOT / "mappings/hfb320.toml"

# %% [markdown]
# ## 1. A record as numpy arrays, and a whole replay without a Python loop

# %%
if HFB.exists():
    data = aeroident.read(HFB, MAPPING)
    print(f"{len(data['t_s'])} samples, {len(data['rejected_rows'])} rows rejected")
    print("alpha range, deg:", np.degrees([np.nanmin(data["alpha_rad"]), np.nanmax(data["alpha_rad"])]))
    r = aeroident.replay(HFB, mapping=MAPPING, estimator="rls", model="longitudinal")
    final = dict(zip(r["names"], r["estimates"][-1]))
    sigma = dict(zip(r["names"], r["std_error"][-1]))
    for name in ("CL_alpha", "Cm_alpha", "Cm_q", "Cm_de"):
        print(f"{name:9s} = {final[name]:+9.4f} ± {sigma[name]:.4f}")
    # estimates is (time × parameter); NaN until a parameter is identified.
    print("estimates matrix:", r["estimates"].shape, "first identified at t =",
          r["t_s"][np.argmax(~np.isnan(r["estimates"]).all(axis=1))], "s")
else:
    print(f"{HFB} not found: skipping the flight record")

# %% [markdown]
# ## 1b. The post-flight reference: output error on the same record
#
# `fit` is `aeroident replay --estimator oe|fem`: the whole record, maximum likelihood, with the
# coloured-residual σ, the correlation matrix, the residuals and the model-vs-measured traces.

# %%
if HFB.exists():
    oe = aeroident.fit(HFB, MAPPING, "oe", model=ROOT / "models/hfb320_book_q0.toml")
    for name, v, s in zip(oe["names"], oe["estimate"], oe["std_error"]):
        print(f"{name:9s} = {v:+9.4f} ± {s:.4f}")
    print(f"{len(oe['summary']['iterations']) - 1} iterations in {oe['summary']['fit_wall_s']:.2f} s;",
          "residual RMS:", dict(oe["summary"]["residual_rms"]))

# %% [markdown]
# ## 2. An estimator object, one sample at a time (e.g. fed from a live link)

# %%
t = 0.02 * np.arange(500)
alpha = 0.05 + 0.02 * np.sin(1.3 * t)
q = 0.03 * np.cos(2.1 * t)
de = -0.02 + 0.01 * np.sin(3.7 * t)
vt, qbar, S, c, m, Iyy = 100.0, 5000.0, 30.0, 3.0, 7000.0, 5.0e4
cm = 0.02 - 0.6 * alpha - 12.0 * q * c / (2 * vt) - 1.1 * de  # the truth to recover
cl, cd = 0.1 + 5.0 * alpha, 0.03 + 0.4 * alpha
est = aeroident.Rls(model="longitudinal", constants=dict(mass_kg=m, S_m2=S, cbar_m=c, Iyy_kgm2=Iyy))
for k in range(len(t)):
    est.update(dict(
        t_s=t[k], vt_mps=vt, alpha_rad=alpha[k], qbar_pa=qbar, q_rad_s=q[k], de_rad=de[k],
        qdot_rad_s2=cm[k] * qbar * S * c / Iyy,
        ax_mps2=qbar * S * (-cd[k] * np.cos(alpha[k]) + cl[k] * np.sin(alpha[k])) / m,
        az_mps2=qbar * S * (-cd[k] * np.sin(alpha[k]) - cl[k] * np.cos(alpha[k])) / m,
    ))
e = est.estimates()
print({n: round(float(v), 4) for n, v in zip(e["names"], e["estimate"]) if n.startswith("Cm")}, e["estimator_status"])

# %% [markdown]
# ## 3. The F-16: trim, linear model, a simulation

# %%
tr = aeroident.trim(alt_ft=10000, vt_fps=600)
print(f"trim: alpha {tr['alpha_deg']:.3f} deg, elevator {tr['elevator_deg']:.3f} deg, throttle {tr['throttle']:.3f}")
lin = aeroident.linearize(alt_ft=10000, vt_fps=600)
print("A", lin["a"].shape, "B", lin["b"].shape)
for mode in lin["modes"]:
    print(f"  {mode['name']:<18} wn {mode['wn_radps']:.3f} rad/s  zeta {mode['zeta']:.3f}")
sim = aeroident.simulate(ROOT / "scenarios/sim/elevator_doublet.toml")
print("simulated", len(sim["t_s"]), "steps; columns:", ", ".join(list(sim)[:6]), "…")

# %% [markdown]
# ## 4. Monte Carlo: locally, or on Ray
#
# On a cluster: `import ray; ray.init(address="ray://head:10001")` first, then
# `backend="ray"`; the statistics are identical to the local ones for the same seed.

# %%
mc = aeroident.montecarlo(ROOT / "scenarios/montecarlo/short.toml", runs=4, seed=1, backend="local")
for est_stats in mc["estimators"]:
    p = next(p for p in est_stats["parameters"] if p["name"] == "Cm_alpha")
    print(f"{est_stats['name']}: Cm_alpha bias {p['bias']:+.2e}, scatter {p['scatter']:.2e}, CRB σ {p['crb_std_error']}")
