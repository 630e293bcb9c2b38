//! The kernel against analytic results built independently of its formulas: rotation matrices
//! multiplied from elementary rotations, Euler's equations in vector form, derivatives of the
//! wind-axes angles by central differences, and hand-solved cases.

use super::*;
use libm::{asin, atan2, cos, sin, sqrt};

const PI: f64 = core::f64::consts::PI;
const G: f64 = 9.80665;

/// The F-16's inertia, slug·ft² (SLJ §3.5).
const F16: Inertia = Inertia { jx: 9_496.0, jy: 55_814.0, jz: 63_100.0, jxz: 982.0 };

fn rel_err(got: f64, want: f64) -> f64 {
    (got - want).abs() / want.abs().max(1e-300)
}

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
}

/// `J ω` with the full tensor `[[Jx, 0, −Jxz], [0, Jy, 0], [−Jxz, 0, Jz]]`.
fn tensor_times(i: &Inertia, w: [f64; 3]) -> [f64; 3] {
    [i.jx * w[0] - i.jxz * w[2], i.jy * w[1], i.jz * w[2] - i.jxz * w[0]]
}

fn mat_mul(a: [[f64; 3]; 3], b: [[f64; 3]; 3]) -> [[f64; 3]; 3] {
    let mut c = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            c[i][j] = (0..3).map(|k| a[i][k] * b[k][j]).sum();
        }
    }
    c
}

/// `C_body←NED = R_x(φ) R_y(θ) R_z(ψ)`, the product of the three elementary frame rotations
/// (SLJ §1.3), multiplied out numerically rather than written in closed form.
fn dcm(phi: f64, theta: f64, psi: f64) -> [[f64; 3]; 3] {
    let (sf, cf, st, ct, sp, cp) = (sin(phi), cos(phi), sin(theta), cos(theta), sin(psi), cos(psi));
    let rx = [[1.0, 0.0, 0.0], [0.0, cf, sf], [0.0, -sf, cf]];
    let ry = [[ct, 0.0, -st], [0.0, 1.0, 0.0], [st, 0.0, ct]];
    let rz = [[cp, sp, 0.0], [-sp, cp, 0.0], [0.0, 0.0, 1.0]];
    mat_mul(rx, mat_mul(ry, rz))
}

const ATTITUDES: [[f64; 3]; 4] =
    [[0.0, 0.0, 0.0], [0.3, 0.2, 1.0], [-2.0, -1.1, 2.5], [2.9, 1.4, -0.4]];

/// No force but gravity and no rotation: the body axes keep their attitude, so the body-axes
/// acceleration is gravity rotated into them, `C·[0, 0, g]`, whatever the velocity.
#[test]
fn analytic_free_fall_is_gravity_rotated_into_body_axes() {
    for [phi, theta, psi] in ATTITUDES {
        let c = dcm(phi, theta, psi);
        let gb = gravity_body(G, SinCos::of(phi), SinCos::of(theta));
        let vd = body_acceleration([250.0, -10.0, 20.0], [0.0; 3], gb, [0.0; 3]);
        for k in 0..3 {
            assert!((vd[k] - c[k][2] * G).abs() < 1e-14 * G, "{k}: {vd:?}");
        }
        // Back in NED: Cᵀ·v̇ = [0, 0, g], a fall straight down.
        let ned: [f64; 3] = core::array::from_fn(|j| (0..3).map(|k| c[k][j] * vd[k]).sum());
        assert!((ned[0].abs() + ned[1].abs() + (ned[2] - G).abs()) < 1e-14 * G, "{ned:?}");
    }
}

/// Newton's law in the rotating body axes in vector form, `v̇ = a + g_b − ω × v`, for rates
/// about every axis (the component formulas of the kernel against the cross product).
#[test]
fn analytic_force_equations_are_newtons_law_in_rotating_axes() {
    let (v, omega, a) = ([180.0, -12.0, 25.0], [0.4, -0.3, 0.7], [1.5, -2.0, -11.0]);
    let gb = gravity_body(G, SinCos::of(0.3), SinCos::of(-0.2));
    let vd = body_acceleration(v, omega, gb, a);
    let wxv = cross(omega, v);
    for k in 0..3 {
        assert!((vd[k] - (a[k] + gb[k] - wxv[k])).abs() < 1e-12, "{k}: {vd:?}");
    }
}

/// Level flight at α = β = 0: without lift the velocity turns down at α̇ = g/V with V̇ = 0;
/// a specific force of −g along z (lift equal to the weight) cancels every rate.
#[test]
fn analytic_level_flight_with_and_without_lift() {
    let (vt, level) = (100.0, SinCos::of(0.0));
    let v = body_velocity(vt, level, level);
    assert_eq!(v, [vt, 0.0, 0.0]);
    let gb = gravity_body(G, level, level);
    let fall = body_acceleration(v, [0.0; 3], gb, [0.0; 3]);
    assert_eq!(wind_axes_rates(v, fall, vt, 1.0), [0.0, G / vt, 0.0]);
    let lifted = body_acceleration(v, [0.0; 3], gb, [0.0, 0.0, -G]);
    assert_eq!(lifted, [0.0; 3]);
    assert_eq!(wind_axes_rates(v, lifted, vt, 1.0), [0.0; 3]);
}

/// A steady pull-up at pitch rate q with V constant along body x: the specific force
/// `a_z = −q V − g` (centripetal plus weight) holds w at 0, as `ẇ = q u + g + a_z` says.
#[test]
fn analytic_pull_up_needs_q_v_of_extra_lift() {
    let (vt, q) = (200.0, 0.1);
    let v = body_velocity(vt, SinCos::of(0.0), SinCos::of(0.0));
    let gb = gravity_body(G, SinCos::of(0.0), SinCos::of(0.0));
    let vd = body_acceleration(v, [0.0, q, 0.0], gb, [0.0, 0.0, -q * vt - G]);
    assert_eq!(vd, [0.0; 3]);
}

/// (V, α, β) → (u, v, w) → (V, α, β) over the whole domain of the angles, and the wind-axes rates
/// against central differences of `V = |v|`, `α = atan2(w, u)`, `β = asin(v/V)` along a step
/// of the body velocity.
#[test]
fn analytic_wind_axes_and_body_axes_round_trip() {
    let v_dot = [1.3, -0.7, 2.1];
    for vt in [1.0, 90.0, 700.0] {
        for alpha in [-3.0, -1.2, -0.1, 0.0, 0.35, 1.5, 3.1] {
            for beta in [-1.4, -0.4, 0.0, 0.2, 1.3] {
                let v = body_velocity(vt, SinCos::of(alpha), SinCos::of(beta));
                let angles = |v: [f64; 3]| {
                    let n = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
                    [n, atan2(v[2], v[0]), asin(v[1] / n)]
                };
                let back = angles(v);
                assert!(rel_err(back[0], vt) < 1e-14, "{back:?}");
                assert!((back[1] - alpha).abs() < 1e-12 && (back[2] - beta).abs() < 1e-12);
                let h = 1e-5 * vt;
                let step = |s: f64| angles(core::array::from_fn(|k| v[k] + s * h * v_dot[k]));
                let (up, down) = (step(1.0), step(-1.0));
                let rates = wind_axes_rates(v, v_dot, vt, cos(beta));
                for k in 0..3 {
                    let fd = (up[k] - down[k]) / (2.0 * h);
                    let scale = fd.abs().max(if k == 0 { 1.0 } else { 1.0 / vt });
                    assert!((rates[k] - fd).abs() < 1e-6 * scale, "{k} {vt} {alpha} {beta}");
                }
            }
        }
    }
}

/// Euler-angle rates against hand values and against the forward relation from Euler rates to
/// body rates (SLJ §1.3): `p = φ̇ − ψ̇ sinθ`, `q = θ̇ cosφ + ψ̇ sinφ cosθ`,
/// `r = −θ̇ sinφ + ψ̇ cosφ cosθ`.
#[test]
fn analytic_euler_rates_invert_the_body_rates_relation() {
    let level = SinCos::of(0.0);
    assert_eq!(euler_rates([0.1, 0.2, 0.3], level, level), [0.1, 0.2, 0.3]);
    // Right wing down 90°: a body pitch rate turns the heading, a body yaw rate lowers the nose.
    let [phid, thetad, psid] = euler_rates([0.0, 0.2, 0.3], SinCos::of(PI / 2.0), level);
    assert!(phid.abs() < 1e-15 && (thetad + 0.3).abs() < 1e-15 && (psid - 0.2).abs() < 1e-15);
    for [phi, theta, _] in ATTITUDES {
        let omega = [0.4, -0.5, 0.6];
        let [fd, td, pd] = euler_rates(omega, SinCos::of(phi), SinCos::of(theta));
        let back = [
            fd - pd * sin(theta),
            td * cos(phi) + pd * sin(phi) * cos(theta),
            -td * sin(phi) + pd * cos(phi) * cos(theta),
        ];
        for k in 0..3 {
            assert!((back[k] - omega[k]).abs() < 1e-12, "{k}: {back:?}");
        }
    }
}

/// A rolling moment alone, from rest: `ṗ = L/Jx` without product of inertia; with `Jxz` the
/// 2×2 system `[[Jx, −Jxz], [−Jxz, Jz]]·[ṗ, ṙ] = [L, 0]` solved by hand also yaws the body.
#[test]
fn analytic_pure_roll_moment() {
    let (jx, jy, jz, l) = (10_000.0, 50_000.0, 60_000.0, 2_000.0);
    let uncoupled = InertiaConstants::from_inertia(jx, jy, jz, 0.0).unwrap();
    let acc = angular_acceleration(&uncoupled, [0.0; 3], [l, 0.0, 0.0], 0.0);
    assert_eq!(acc, [l / jx, 0.0, 0.0]);
    let jxz = 1_500.0;
    let det = jx * jz - jxz * jxz;
    let coupled = InertiaConstants::from_inertia(jx, jy, jz, jxz).unwrap();
    let [pdot, qdot, rdot] = angular_acceleration(&coupled, [0.0; 3], [l, 0.0, 0.0], 0.0);
    assert!(rel_err(pdot, jz * l / det) < 1e-15 && rel_err(rdot, jxz * l / det) < 1e-15);
    assert_eq!(qdot, 0.0);
}

/// Euler's equations by hand for a diagonal tensor `J = diag(1, 2, 3)` at `ω = (1, 1, 1)`, no
/// moment: `ṗ = (Jy − Jz) q r / Jx = −1`, `q̇ = (Jz − Jx) r p / Jy = 1`,
/// `ṙ = (Jx − Jy) p q / Jz = −1/3`.
#[test]
fn analytic_eulers_equations_hand_computed() {
    let c = InertiaConstants::from_inertia(1.0, 2.0, 3.0, 0.0).unwrap();
    let [p, q, r] = angular_acceleration(&c, [1.0; 3], [0.0; 3], 0.0);
    assert!((p + 1.0).abs() < 1e-15 && (q - 1.0).abs() < 1e-15 && (r + 1.0 / 3.0).abs() < 1e-15);
}

/// With the full tensor, rates on every axis and a rotor: `J ω̇ = M − ω × (J ω + h e_x)` holds
/// for the kernel's ω̇, and the inverse gives back the applied moments.
#[test]
fn analytic_eulers_equations_and_their_inverse() {
    let c = InertiaConstants::from_inertia(F16.jx, F16.jy, F16.jz, F16.jxz).unwrap();
    let (omega, moment, h) = ([0.7, -0.8, 0.9], [12_000.0, -30_000.0, 5_000.0], 160.0);
    let wd = angular_acceleration(&c, omega, moment, h);
    let jw = tensor_times(&F16, omega);
    let gyro = cross(omega, [jw[0] + h, jw[1], jw[2]]);
    let lhs = tensor_times(&F16, wd);
    for k in 0..3 {
        assert!((lhs[k] - (moment[k] - gyro[k])).abs() < 1e-11 * 30_000.0, "{k}: {lhs:?}");
    }
    let [l, n] = roll_yaw_moments(&F16, omega, wd[0], wd[2], h);
    let m = pitch_moment(&F16, omega[0], omega[2], wd[1], h);
    for (got, want) in [(l, moment[0]), (m, moment[1]), (n, moment[2])] {
        assert!((got - want).abs() < 1e-11 * 30_000.0, "{got} vs {want}");
    }
    // Symmetric flight: no coupling term at all, so M = Jy q̇ exactly.
    assert_eq!(pitch_moment(&F16, 0.0, 0.0, 0.25, 0.0), F16.jy * 0.25);
}

/// The constants of the F-16's inertia against the rounded values SLJ §3.5 prints.
#[test]
fn val_inertia_constants_match_slj_f16() {
    let c = InertiaConstants::from_inertia(F16.jx, F16.jy, F16.jz, F16.jxz).unwrap();
    let printed = [
        (c.c1, -0.770),
        (c.c2, 0.02755),
        (c.c3, 1.055e-4),
        (c.c4, 1.642e-6),
        (c.c5, 0.9604),
        (c.c6, 1.759e-2),
        (c.c7, 1.792e-5),
        (c.c8, -0.7336),
        (c.c9, 1.587e-5),
    ];
    for (exact, rounded) in printed {
        assert!(rel_err(exact, rounded) < 2e-3, "{exact} vs {rounded}");
    }
    assert_eq!(InertiaConstants::of(&F16), c);
}

#[test]
fn errors_inertia_that_is_not_a_body_is_refused() {
    let field = |r: Result<InertiaConstants, InertiaError>| r.unwrap_err().field;
    assert_eq!(field(InertiaConstants::from_inertia(0.0, 1.0, 1.0, 0.0)), "jx");
    assert_eq!(field(InertiaConstants::from_inertia(1.0, f64::NAN, 1.0, 0.0)), "jy");
    assert_eq!(field(InertiaConstants::from_inertia(1.0, 1.0, -1.0, 0.0)), "jz");
    assert_eq!(field(InertiaConstants::from_inertia(1.0, 1.0, 1.0, 1.0)), "jxz");
    assert_eq!(field(InertiaConstants::from_inertia(1.0, 1.0, 1.0, f64::INFINITY)), "jxz");
    // Only Jy known: the unchecked constants keep a usable pitch equation.
    let pitch_only = InertiaConstants::of(&Inertia { jy: 4.0, ..Inertia::default() });
    assert_eq!((pitch_only.c5, pitch_only.c6, pitch_only.c7), (0.0, 0.0, 0.25));
    assert!(!pitch_only.c3.is_finite());
    assert_eq!(pitch_acceleration(&pitch_only, 0.0, 0.0, 2.0, 0.0), 0.5);
}
