"""`aeroident.Aircraft`: a user's own loop around the simulator, checked against properties
computed here (a trim that holds, a Jacobian by central differences, RK4's order, an increment
worked by hand) and against the closed-loop example's physical outcome."""

from __future__ import annotations

import importlib.util
import json
import math

import numpy as np
import pytest

import aeroident
from conftest import ROOT

VT, ALT = 675 * 0.3048, 20_000 * 0.3048
Q, ALPHA, VT_I = 7, 1, 0


@pytest.fixture(scope="module")
def f16():
    ac = aeroident.Aircraft.f16(xcg=0.30)
    return ac, ac.trim(VT, ALT)


def test_a_trim_holds_under_step(f16):
    ac, t = f16
    assert len(t["state"]) == len(ac.state_names) == 13 and t["state_names"][0] == "vt_mps"
    x = t["state"]
    for k in range(200):
        x = ac.step(x, t["controls"], 0.01, t_s=k * 0.01)
    # 2 s of flight at the trim: the airspeed (m/s), alpha and q stay put.
    assert abs(x[VT_I] - t["state"][VT_I]) < 1e-4
    assert abs(x[ALPHA] - t["state"][ALPHA]) < 1e-7 and abs(x[Q]) < 1e-7


def test_linearize_is_the_jacobian_of_derivatives(f16):
    ac, t = f16
    lin = ac.linearize(VT, ALT)
    x0, u0 = lin["trim"]["state"], lin["trim"]["controls"]
    n = len(x0)
    a = np.zeros((n, n))
    for j in range(n):
        h = 1e-5 * max(1.0, abs(x0[j]))
        e = np.zeros(n)
        e[j] = h
        a[:, j] = (ac.derivatives(x0 + e, u0) - ac.derivatives(x0 - e, u0)) / (2 * h)
    b = np.zeros((n, 4))
    for j in range(4):
        h = 1e-5 * max(1.0, abs(u0[j]))
        up, um = list(u0), list(u0)
        up[j] += h
        um[j] -= h
        b[:, j] = (ac.derivatives(x0, up) - ac.derivatives(x0, um)) / (2 * h)
    np.testing.assert_allclose(lin["a"], a, rtol=1e-4, atol=1e-6)
    np.testing.assert_allclose(lin["b"], b, rtol=1e-4, atol=1e-6)
    assert lin["c"].shape == (n, n) and lin["d"].shape == (n, 4)
    names = {m["name"] for m in lin["modes"]}
    assert {"short_period", "dutch_roll", "phugoid"} <= names, names


def test_step_is_fourth_order(f16):
    ac, t = f16
    u = list(t["controls"])
    u[1] += math.radians(1.0)
    x0 = t["state"]

    def fly(dt, total=1.0):
        x = x0
        for k in range(round(total / dt)):
            x = ac.step(x, u, dt, t_s=k * dt)
        return x

    fine = fly(0.0025)
    e1 = np.abs(fly(0.02)[Q] - fine[Q])
    e2 = np.abs(fly(0.01)[Q] - fine[Q])
    # Global error O(dt^4): halving dt divides it by ~16 (the fine run's own error is 256x
    # smaller than the coarse one's).
    assert 10 < e1 / e2 < 22, (e1, e2)


def test_damage_adds_the_increment_worked_by_hand(f16):
    ac, t = f16
    damaged = ac.with_damage({"Cm_alpha": -0.1}, about=t, onset_s=5.0)
    x = t["state"].copy()
    x[ALPHA] += math.radians(1.0)
    before = damaged.derivatives(x, t["controls"], t_s=4.0)
    after = damaged.derivatives(x, t["controls"], t_s=5.0)
    s = damaged.sample(x, t["controls"])
    # dq/dt changes by qbar S cbar dCm_alpha dalpha / Iyy (SI; state in rad/s). The model flies
    # Stevens & Lewis's tabulated c7 = 1.792e-5 /(slug ft^2), 1/Iyy rounded (1/55814 =
    # 1.79167e-5): 1.9e-4 above the exact inverse.
    expected = s["qbar_pa"] * s["S_m2"] * s["cbar_m"] * -0.1 * math.radians(1.0) / s["Iyy_kgm2"]
    assert after[Q] - before[Q] == pytest.approx(expected * 1.792e-5 * 55814.0, rel=1e-9)
    np.testing.assert_array_equal(before, ac.derivatives(x, t["controls"]))


def test_sample_feeds_an_estimator(f16):
    ac, t = f16
    s = ac.sample(t["state"], t["controls"], t_s=1.5)
    xd = ac.derivatives(t["state"], t["controls"])
    assert s["t_s"] == 1.5 and s["qdot_rad_s2"] == pytest.approx(xd[Q], abs=1e-12)
    assert s["vt_mps"] == pytest.approx(t["state"][VT_I], rel=1e-12)
    assert s["vt_mps"] == pytest.approx(t["state_textbook"][VT_I] * 0.3048, rel=1e-12)
    est = aeroident.Estimator("rls", model="longitudinal")
    est.update(s)
    assert est.samples == 1


def test_bad_arguments_are_named(f16):
    ac, t = f16
    with pytest.raises(aeroident.AeroidentError, match="13 states"):
        ac.step(t["state"][:12], t["controls"], 0.01)
    with pytest.raises(aeroident.AeroidentError, match="4 expected"):
        ac.step(t["state"], t["controls"][:3], 0.01)
    with pytest.raises(aeroident.AeroidentError, match="positive and finite"):
        ac.step(t["state"], t["controls"], 0.0)
    with pytest.raises(aeroident.AeroidentError, match="Cm_bogus"):
        ac.with_damage({"Cm_bogus": 1.0}, about=t)
    with pytest.raises(aeroident.AeroidentError, match="xcg"):
        aeroident.Aircraft.f16(xcg=0.9)


def test_the_adaptive_example_restores_the_tracking_after_the_damage():
    spec = importlib.util.spec_from_file_location("adaptive", ROOT / "examples" / "python_adaptive_pitch.py")
    ex = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(ex)
    fixed, adaptive = ex.run(False), ex.run(True)
    before = ex.rms_error(fixed, 2.0, ex.ONSET_S)
    after_fixed = ex.rms_error(fixed, ex.ONSET_S + 2.0, ex.DURATION_S)
    after_adaptive = ex.rms_error(adaptive, ex.ONSET_S + 2.0, ex.DURATION_S)
    # The damage degrades the fixed loop; the adaptive one tracks better after it.
    assert after_fixed > 1.2 * before, (before, after_fixed)
    assert after_adaptive < 0.9 * after_fixed, (after_adaptive, after_fixed)


def test_a_model_file_aircraft_without_values_is_refused_by_name():
    with pytest.raises(aeroident.AeroidentError, match=r"no \[reference.CL_0\] value"):
        aeroident.Aircraft.from_model(str(ROOT / "models/hfb320_jategaonkar.toml"), str(ROOT / "mappings/hfb320.toml"))


FT = 0.3048  # exact; independent of aeroident's constant
F16_FACTORS = np.array([FT, 1, 1, 1, 1, 1, 1, 1, 1, FT, FT, FT, 1])


def test_the_f16_states_are_si_and_the_textbook_units_only_by_name(f16):
    ac, t = f16
    assert ac.state_names[0] == "vt_mps" and ac.state_names[9:12] == ["north_m", "east_m", "alt_m"]
    assert ac.state_names_textbook[0] == "vt_fps" and ac.state_names_textbook[11] == "alt_ft"
    for key, shape in (("state", (13,)), ("state_textbook", (13,)), ("controls", (4,))):
        assert isinstance(t[key], np.ndarray) and t[key].dtype == np.float64 and t[key].shape == shape
    np.testing.assert_array_equal(t["state"], t["state_textbook"] * F16_FACTORS)
    assert t["state"][0] == pytest.approx(VT, rel=1e-9) and t["state"][11] == pytest.approx(ALT, rel=1e-9)
    np.testing.assert_array_equal(ac.to_textbook(t["state"]), t["state"] / F16_FACTORS)
    np.testing.assert_allclose(ac.from_textbook(ac.to_textbook(t["state"])), t["state"], rtol=1e-15)
    # A derivative in SI is the textbook derivative times the same factors: a climb of 1 ft/s
    # (the textbook's d alt_ft/dt) is 0.3048 m/s.
    x = t["state"].copy()
    x[4] += 0.01  # nose up: the aircraft climbs and slows
    xd = ac.derivatives(x, t["controls"])
    xd_ft = ac.derivatives(ac.from_textbook(ac.to_textbook(x)), t["controls"]) / F16_FACTORS
    np.testing.assert_allclose(xd, xd_ft * F16_FACTORS, rtol=1e-12)
    assert xd[11] > 0 and xd[0] < 0
    # Independently of the conversion: wings level without sideslip the climb rate is
    # V sin(θ − α) in the state's own units, m/s here (ft/s would be 3.28 times larger).
    assert abs(x[2]) < 1e-9 and abs(x[3]) < 1e-9
    assert xd[11] == pytest.approx(x[0] * math.sin(x[4] - x[1]), rel=1e-9)


def test_state_and_controls_take_any_array_like(f16):
    ac, t = f16
    x, u = t["state"], t["controls"]
    one = ac.step(x, u, 0.01)
    np.testing.assert_array_equal(ac.step(list(x), tuple(u), 0.01), one)
    np.testing.assert_array_equal(ac.step(x.tolist(), np.asarray(u).tolist(), 0.01), one)
    # A strided view, not a contiguous array.
    doubled = np.repeat(x, 2)[::2]
    np.testing.assert_array_equal(ac.derivatives(doubled, u), ac.derivatives(x, u))
    assert one.dtype == np.float64 and one.shape == (13,)


def test_the_linear_model_in_si_is_the_textbook_one_scaled(f16):
    ac, _ = f16
    lin = ac.linearize(VT, ALT)
    d = F16_FACTORS
    assert lin["a"].shape == (13, 13) and lin["b"].shape == (13, 4) and lin["eigenvalues"].shape == (13, 2)
    np.testing.assert_allclose(lin["a"], d[:, None] * lin["a_textbook"] / d[None, :], rtol=1e-14, atol=1e-300)
    np.testing.assert_allclose(lin["b"], d[:, None] * lin["b_textbook"], rtol=1e-14, atol=1e-300)
    assert lin["states"][0] == "vt_mps" and lin["states_textbook"][0] == "vt_fps"


UAV_VALUES = {
    "CL_0": 0.3, "CL_alpha": 4.8, "CL_q": 6.0, "CL_de": 0.35, "CD_0": 0.03, "CD_alpha": 0.1125,
    "CD_alpha2": 0.9, "CY_beta": -0.3, "CY_p": -0.05, "CY_r": 0.2, "CY_dr": 0.15,
    "Cl_beta": -0.08, "Cl_p": -0.45, "Cl_r": 0.1, "Cl_da": -0.25, "Cl_dr": 0.005, "Cm_0": 0.02,
    "Cm_alpha": -0.6, "Cm_q": -9.0, "Cm_de": -1.0, "Cn_beta": 0.06, "Cn_p": -0.03,
    "Cn_r": -0.08, "Cn_da": 0.004, "Cn_dr": -0.05,
}


def write_uav(tmp_path, de_line):
    """A 3.3-kg UAV's model file (references = values) and mapping with elevator line de_line."""
    model = ['description = "test UAV"', "[coefficients]"]
    for c in ("CL", "CD", "CY", "Cl", "Cm", "Cn"):
        terms = [n.split("_", 1)[1] for n in UAV_VALUES if n.split("_", 1)[0] == c]
        model.append(f"{c} = {json.dumps(terms)}")
    for n, v in UAV_VALUES.items():
        model += [f"[reference.{n}]", f"value = {v}", 'source = "test"']
    (tmp_path / "model.toml").write_text("\n".join(model) + "\n")
    consts = {"mass": (3.3, "kg"), "Ixx": (0.17, "kg*m2"), "Iyy": (0.289, "kg*m2"),
              "Izz": (0.443, "kg*m2"), "Ixz": (0.019, "kg*m2"), "S": (0.384, "m2"),
              "b": (1.6, "m"), "cbar": (0.24, "m")}
    mapping = ['description = "test"', "[time]", 'column = "t"', 'unit = "s"', "[channels]",
               'vt = { column = "v", unit = "m/s" }', 'alpha = { column = "a", unit = "rad" }',
               'qbar = { column = "qbar", unit = "Pa" }', de_line]
    mapping += [f'{k} = {{ value = {v}, unit = "{u}" }}' for k, (v, u) in consts.items()]
    (tmp_path / "map.toml").write_text("\n".join(mapping) + "\n")
    return str(tmp_path / "model.toml"), str(tmp_path / "map.toml")


def test_an_actuator_is_a_state_of_the_linear_model(tmp_path):
    """The mapping's elevator servo (tau 0.05 s) adds the state elevator_rad with pole -1/tau and
    unit DC gain from its command; the rigid-body eigenvalues are those without it."""
    servo = ('de = { column = "de", unit = "rad", actuator = { tau_s = 0.05, '
             'rate_limit_rad_s = 3.5 } }')
    plain = aeroident.Aircraft.from_model(*write_uav(tmp_path, 'de = { column = "de", unit = "rad" }'))
    bare = plain.linearize(18.0, 100.0)
    served = aeroident.Aircraft.from_model(*write_uav(tmp_path, servo)).linearize(18.0, 100.0)
    n = bare["a"].shape[0]
    assert served["a"].shape == (n + 1, n + 1) and served["b"].shape == (n + 1, 4)
    assert served["states"][-1] == "elevator_rad" and served["inputs"][1] == "elevator_cmd_rad"
    assert bare["actuators"] == [] and served["actuators"][0]["tau_s"] == 0.05
    a, b = served["a"], served["b"]
    assert a[n, n] == pytest.approx(-1 / 0.05) and b[n, 1] == pytest.approx(1 / 0.05)
    # The surface state drives the rigid body as the surface column of B did without the servo.
    np.testing.assert_allclose(a[:n, n], bare["b"][:, 1], rtol=1e-9, atol=1e-12)
    assert np.all(b[:n, 1] == 0.0)
    ev = served["eigenvalues"]
    assert np.min(np.abs(ev[:, 0] + 20.0) + np.abs(ev[:, 1])) < 1e-9
    # Every rigid-body eigenvalue is kept (the repeated zero roots of the integrators to their
    # conditioning, 1e-5).
    kept = list(ev[:, 0] + 1j * ev[:, 1])
    kept.pop(int(np.argmin(np.abs(np.array(kept) + 20.0))))
    for lam in bare["eigenvalues"][:, 0] + 1j * bare["eigenvalues"][:, 1]:
        k = int(np.argmin(np.abs(np.array(kept) - lam)))
        assert abs(kept.pop(k) - lam) < 1e-5, lam
