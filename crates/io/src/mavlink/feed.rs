//! aeroident's own MAVLink feed: an [`AirDataSample`] as the messages that
//! `mappings/mavlink-aeroident.toml` reads, and a UDP sender. Used to stream a recorded flight
//! to a live replay (the loopback test) and as the reference of what each message carries.
//!
//! One frame per sample, the clock message `ATTITUDE` last (the receiver holds every other
//! message and emits a row on the clock):
//!
//! | message | fields | channels (units as the MAVLink spec defines them) |
//! |---|---|---|
//! | `HIGHRES_IMU` | `xacc`, `yacc`, `zacc`, `diff_pressure` | ax, ay, az (m/s², body specific force, FRD, ≈ −g on z level); q̄ (hPa) |
//! | `VFR_HUD` | `airspeed` | V (m/s) |
//! | `AOA_SSA` | `AOA`, `SSA` | α, β (deg) |
//! | `NAMED_VALUE_FLOAT[<name>]` | `value` | de, da, dr (rad), throttle (0–1), thrust (N), thr_mom (N·m), rho (kg/m³), mass (kg), S (m²), cbar, b (m), Ixx, Iyy, Izz, Ixz (kg·m², Stevens & Lewis Jxz) |
//! | `ATTITUDE` (clock) | `time_boot_ms`, `roll`, `pitch`, `yaw`, `rollspeed`, `pitchspeed`, `yawspeed` | t (ms), φ, θ, ψ (rad, ψ wrapped to ±π as the spec says), p, q, r (rad/s) |
//!
//! Every value is sent as the message's `f32` (MAVLink floats), so the receiver sees the
//! sample rounded to `f32`; an absent channel is NaN in a standard message (blank in the row)
//! and not sent as a `NAMED_VALUE_FLOAT`.

use super::END_OF_STREAM_NAME;
use aeroident_estimators::AirDataSample;
use mavlink::dialects::ardupilotmega::{
    AOA_SSA_DATA, ATTITUDE_DATA, HIGHRES_IMU_DATA, MavMessage, NAMED_VALUE_FLOAT_DATA, VFR_HUD_DATA,
};
use mavlink::{MavHeader, MavlinkVersion};
use std::net::{SocketAddr, UdpSocket};

/// `f32` of an optional value, NaN when absent.
fn f(v: Option<f64>) -> f32 {
    v.map_or(f32::NAN, |x| x as f32)
}

/// ψ wrapped to (−π, π], as `ATTITUDE.yaw` is specified.
fn wrap_pi(x: f64) -> f64 {
    x.sin().atan2(x.cos())
}

/// The messages of one sample, the clock (`ATTITUDE`) last. `t_s` becomes
/// `time_boot_ms = round(1000 t)`.
pub fn frame(s: &AirDataSample) -> Vec<MavMessage> {
    let boot_ms = (s.t_s * 1000.0).round().clamp(0.0, f64::from(u32::MAX)) as u32;
    let mut out = vec![
        MavMessage::HIGHRES_IMU(HIGHRES_IMU_DATA {
            time_usec: u64::from(boot_ms) * 1000,
            xacc: f(s.ax_mps2),
            yacc: f(s.ay_mps2),
            zacc: f(s.az_mps2),
            diff_pressure: (s.qbar_pa / 100.0) as f32,
            ..Default::default()
        }),
        MavMessage::VFR_HUD(VFR_HUD_DATA { airspeed: s.vt_mps as f32, ..Default::default() }),
        MavMessage::AOA_SSA(AOA_SSA_DATA {
            time_usec: u64::from(boot_ms) * 1000,
            AOA: s.alpha_rad.to_degrees() as f32,
            SSA: f(s.beta_rad.map(f64::to_degrees)),
        }),
    ];
    let c = &s.constants;
    let named = [
        ("de", s.de_rad),
        ("da", s.da_rad),
        ("dr", s.dr_rad),
        ("throttle", s.throttle),
        ("thrust", s.thrust_n),
        ("thr_mom", s.thrust_moment_nm),
        ("rho", s.rho_kgpm3),
        ("mass", Some(c.mass_kg)),
        ("S", Some(c.S_m2)),
        ("cbar", c.cbar_m),
        ("b", c.b_m),
        ("Ixx", c.Ixx_kgm2),
        ("Iyy", c.Iyy_kgm2),
        ("Izz", c.Izz_kgm2),
        ("Ixz", c.Ixz_kgm2),
    ];
    for (name, v) in named {
        if let Some(v) = v {
            out.push(MavMessage::NAMED_VALUE_FLOAT(NAMED_VALUE_FLOAT_DATA {
                time_boot_ms: boot_ms,
                value: v as f32,
                name: name.into(),
            }));
        }
    }
    out.push(MavMessage::ATTITUDE(ATTITUDE_DATA {
        time_boot_ms: boot_ms,
        roll: f(s.phi_rad),
        pitch: f(s.theta_rad),
        yaw: f(s.psi_rad.map(wrap_pi)),
        rollspeed: f(s.p_rad_s),
        pitchspeed: f(s.q_rad_s),
        yawspeed: f(s.r_rad_s),
    }));
    out
}

/// The message that ends a feed cleanly.
pub fn end_of_stream() -> MavMessage {
    MavMessage::NAMED_VALUE_FLOAT(NAMED_VALUE_FLOAT_DATA {
        time_boot_ms: 0,
        value: 0.0,
        name: END_OF_STREAM_NAME.into(),
    })
}

/// Sends MAVLink 2 messages, one per datagram, with consecutive sequence numbers.
pub struct Sender {
    socket: UdpSocket,
    to: SocketAddr,
    header: MavHeader,
    buf: Vec<u8>,
}

impl Sender {
    /// A sender from an ephemeral local port to `to`, as system 1, component 1 (autopilot).
    ///
    /// # Errors
    /// The socket's I/O error.
    pub fn new(to: SocketAddr) -> std::io::Result<Self> {
        let local: SocketAddr =
            if to.is_ipv4() { ([0, 0, 0, 0], 0).into() } else { ([0u16; 8], 0).into() };
        Ok(Self {
            socket: UdpSocket::bind(local)?,
            to,
            header: MavHeader { system_id: 1, component_id: 1, sequence: 0 },
            buf: Vec::with_capacity(300),
        })
    }

    /// Sends one message in its own datagram.
    ///
    /// # Errors
    /// Encoding or socket errors.
    pub fn send(&mut self, msg: &MavMessage) -> std::io::Result<()> {
        self.buf.clear();
        mavlink::write_versioned_msg(&mut self.buf, MavlinkVersion::V2, self.header, msg)
            .map_err(|e| std::io::Error::other(e.to_string()))?;
        self.socket.send_to(&self.buf, self.to)?;
        self.header.sequence = self.header.sequence.wrapping_add(1);
        Ok(())
    }

    /// Sends raw bytes as one datagram (e.g. to test how a receiver treats garbage).
    ///
    /// # Errors
    /// The socket's I/O error.
    pub fn send_raw(&mut self, bytes: &[u8]) -> std::io::Result<()> {
        self.socket.send_to(bytes, self.to).map(|_| ())
    }
}
