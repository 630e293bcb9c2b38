//! The samples a C caller feeds the library, as CSV (Rust only; not part of the C ABI): the
//! columns of [`crate::AeroidentSample`], one row per sample with its manoeuvre number, each
//! number so that it reads back to the same `double`. `examples/conditioned_samples.rs` writes
//! the samples `aeroident replay` feeds its estimator for a record
//! (`aeroident_pipelines::replay::fed::fed_samples`) in this form, for
//! `examples/c/replay_samples.c` to feed the C library the same ones.

use aeroident_estimators::AirDataSample;
use aeroident_estimators::sample::MEASURED_FIELDS;
use std::io::Write;

/// One row: the manoeuvre the sample belongs to (numbered from 0; a new one at each gap,
/// `aeroident_estimator_new_manoeuvre`) and the sample.
pub type SampleRow = (u32, AirDataSample);

/// The columns of [`write_samples_csv`]: `manoeuvre`, then the fields of [`crate::AeroidentSample`]
/// in its order (without `present`: an absent field is an empty cell): `t_s`, the sample's
/// [`MEASURED_FIELDS`] (taken from that list; the writer reads them by name,
/// `AirDataSample::field`), the constants. The test `header` holds the C struct to it.
pub const SAMPLE_COLUMNS: [&str; 37] = {
    let mut columns = [""; 37];
    columns[0] = "manoeuvre";
    columns[1] = "t_s";
    let mut i = 0;
    while i < MEASURED_FIELDS.len() {
        columns[2 + i] = MEASURED_FIELDS[i];
        i += 1;
    }
    let mut k = 0;
    while k < CONSTANT_COLUMNS.len() {
        columns[2 + MEASURED_FIELDS.len() + k] = CONSTANT_COLUMNS[k];
        k += 1;
    }
    columns
};

/// The aircraft constants of [`crate::AeroidentSample`], in its order: the last columns of
/// [`SAMPLE_COLUMNS`].
const CONSTANT_COLUMNS: [&str; 11] = [
    "mass_kg",
    "S_m2",
    "cbar_m",
    "b_m",
    "Ixx_kgm2",
    "Iyy_kgm2",
    "Izz_kgm2",
    "Ixz_kgm2",
    "thrust_arm_m",
    "thrust_incidence_rad",
    "v0_mps",
];

/// Writes `samples` as CSV: a header of [`SAMPLE_COLUMNS`], then one row per sample, each
/// number in the shortest form that reads back (`strtod`, Rust's `parse`) to the same
/// `double`, an absent field empty.
///
/// # Errors
/// A failed write.
pub fn write_samples_csv(w: &mut dyn Write, samples: &[SampleRow]) -> std::io::Result<()> {
    writeln!(w, "{}", SAMPLE_COLUMNS.join(","))?;
    for (manoeuvre, s) in samples {
        let k = s.constants;
        let constants = [k.cbar_m, k.b_m, k.Ixx_kgm2, k.Iyy_kgm2, k.Izz_kgm2, k.Ixz_kgm2];
        write!(w, "{},{}", manoeuvre, s.t_s)?;
        MEASURED_FIELDS.iter().try_for_each(|name| cell(w, s.field(name)))?;
        write!(w, ",{},{}", k.mass_kg, k.S_m2)?;
        constants.iter().try_for_each(|v| cell(w, *v))?;
        write!(w, ",{},{}", k.thrust_arm_m, k.thrust_incidence_rad)?;
        cell(w, k.v0_mps)?;
        writeln!(w)?;
    }
    Ok(())
}

/// `,value` or `,` for an absent one.
fn cell(w: &mut dyn Write, v: Option<f64>) -> std::io::Result<()> {
    match v {
        Some(v) => write!(w, ",{v}"),
        None => write!(w, ","),
    }
}

/// Reads what [`write_samples_csv`] wrote back (for tests and tools).
///
/// # Errors
/// A header that is not [`SAMPLE_COLUMNS`], or a cell that is not a number, naming the line
/// and column.
pub fn read_samples_csv(text: &str) -> Result<Vec<SampleRow>, String> {
    let mut lines = text.lines().enumerate();
    let header = lines.next().map(|(_, h)| h).unwrap_or("");
    if header != SAMPLE_COLUMNS.join(",") {
        return Err(format!("line 1: the header is not `{}`", SAMPLE_COLUMNS.join(",")));
    }
    lines.map(|(i, line)| sample_row(line).map_err(|e| format!("line {}: {e}", i + 1))).collect()
}

/// One row of [`read_samples_csv`].
fn sample_row(line: &str) -> Result<SampleRow, String> {
    let cells: Vec<&str> = line.split(',').collect();
    if cells.len() != SAMPLE_COLUMNS.len() {
        return Err(format!("{} cells, expected {}", cells.len(), SAMPLE_COLUMNS.len()));
    }
    let num = |k: usize| -> Result<Option<f64>, String> {
        let c = cells[k];
        if c.is_empty() {
            return Ok(None);
        }
        c.parse()
            .map(Some)
            .map_err(|_| format!("column `{}`: `{c}` is not a number", SAMPLE_COLUMNS[k]))
    };
    let req = |k: usize| num(k)?.ok_or_else(|| format!("column `{}` is empty", SAMPLE_COLUMNS[k]));
    let manoeuvre = cells[0].parse().map_err(|_| format!("manoeuvre `{}`", cells[0]))?;
    let constants = aeroident_estimators::AircraftConstants {
        mass_kg: req(26)?,
        S_m2: req(27)?,
        cbar_m: num(28)?,
        b_m: num(29)?,
        Ixx_kgm2: num(30)?,
        Iyy_kgm2: num(31)?,
        Izz_kgm2: num(32)?,
        Ixz_kgm2: num(33)?,
        thrust_arm_m: req(34)?,
        thrust_incidence_rad: req(35)?,
        v0_mps: num(36)?,
    };
    let sample = AirDataSample {
        t_s: req(1)?,
        vt_mps: req(2)?,
        alpha_rad: req(3)?,
        qbar_pa: req(4)?,
        beta_rad: num(5)?,
        p_rad_s: num(6)?,
        q_rad_s: num(7)?,
        r_rad_s: num(8)?,
        pdot_rad_s2: num(9)?,
        qdot_rad_s2: num(10)?,
        rdot_rad_s2: num(11)?,
        alphadot_rad_s: num(12)?,
        phi_rad: num(13)?,
        theta_rad: num(14)?,
        psi_rad: num(15)?,
        ax_mps2: num(16)?,
        ay_mps2: num(17)?,
        az_mps2: num(18)?,
        de_rad: num(19)?,
        da_rad: num(20)?,
        dr_rad: num(21)?,
        thrust_n: num(22)?,
        throttle: num(23)?,
        thrust_moment_nm: num(24)?,
        rho_kgpm3: num(25)?,
        constants,
    };
    Ok((manoeuvre, sample))
}

#[cfg(test)]
mod tests {
    use super::*;
    use aeroident_estimators::AircraftConstants;

    /// What [`write_samples_csv`] writes reads back bit for bit (the shortest round-trip form of
    /// awkward doubles, absent fields empty, the manoeuvre numbers), and a bad cell is refused
    /// naming its line and column.
    #[test]
    fn samples_csv_round_trips_every_bit() {
        let s = AirDataSample {
            t_s: 0.1 + 0.2,
            vt_mps: 106.0321,
            alpha_rad: 1e-300,
            qbar_pa: 4467.594,
            q_rad_s: Some(-0.0),
            qdot_rad_s2: Some(f64::MIN_POSITIVE),
            de_rad: Some(-1.0 / 3.0),
            constants: AircraftConstants {
                mass_kg: 7472.0,
                S_m2: 30.097216,
                Iyy_kgm2: Some(91389.45),
                thrust_arm_m: -0.6411244,
                v0_mps: Some(104.67),
                ..Default::default()
            },
            ..Default::default()
        };
        let fed = [(0, s), (3, s)];
        let mut text = Vec::new();
        write_samples_csv(&mut text, &fed).unwrap();
        let text = String::from_utf8(text).unwrap();
        let back = read_samples_csv(&text).unwrap();
        assert_eq!(back.len(), 2);
        for (a, b) in back.iter().zip(&fed) {
            assert_eq!(a.0, b.0);
            assert_eq!(format!("{:?}", a.1), format!("{:?}", b.1));
            assert_eq!(a.1.q_rad_s.unwrap().to_bits(), (-0.0f64).to_bits());
            assert_eq!(a.1.t_s.to_bits(), (0.1f64 + 0.2).to_bits());
        }
        let bad = text.replacen("106.0321", "1O6", 1);
        let e = read_samples_csv(&bad).unwrap_err();
        assert!(e.starts_with("line 2: column `vt_mps`"), "{e}");
    }

    /// The header's measured columns are the sample's own list, in its order: the writer
    /// fills them by those names and the reader by position.
    #[test]
    fn the_measured_columns_are_the_samples_list() {
        assert_eq!(SAMPLE_COLUMNS[..2], ["manoeuvre", "t_s"]);
        assert_eq!(SAMPLE_COLUMNS[2..2 + MEASURED_FIELDS.len()], MEASURED_FIELDS);
    }
}
