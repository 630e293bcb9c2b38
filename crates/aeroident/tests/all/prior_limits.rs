//! Extreme priors are refused where they enter, naming the parameter, its value and σ and the
//! file, before any estimator runs: a model file with one (line and prior named), and priors
//! handed to the estimator builder (every estimator that starts from a prior). Within the
//! limits the published sliding-mode estimator is built as before.

use aeroident_estimators::prior::ParamPrior;
use aeroident_estimators::{ModelStructure, Priors};
use aeroident_io::ModelSpec;
use aeroident_pipelines::estimators::{BuildError, EstimatorKind, EstimatorOptions, build};

const MODEL: &str = "[coefficients]\nCm = [\"0\", \"alpha\", \"q\", \"de\"]\n[prior.Cm_alpha]\nvalue = VALUE\nsigma = SIGMA\n";

fn model_file(value: &str, sigma: &str) -> Result<ModelSpec, String> {
    let text = MODEL.replace("VALUE", value).replace("SIGMA", sigma);
    ModelSpec::from_toml_str(&text, "extreme.toml").map_err(|e| e.to_string())
}

#[test]
fn errors_a_model_file_with_an_extreme_prior_names_it() {
    for (value, sigma, says) in [
        ("-0.5", "1e10", "sigma 10000000000 is beyond"),
        ("-0.5", "1e-17", "sigma 0.00000000000000001 is below"),
        ("1e6", "1.0", "value 1000000 is not finite or beyond"),
        ("-0.5", "0.0", "sigma must be finite and > 0"),
    ] {
        let e = model_file(value, sigma).unwrap_err();
        assert!(e.contains("extreme.toml") && e.contains("line 3"), "{e}");
        assert!(e.contains("prior `Cm_alpha`") && e.contains(says), "{value} ± {sigma}: {e}");
    }
    // The limits themselves are accepted.
    assert!(model_file("-1e4", "1e4").is_ok());
    assert!(model_file("-0.5", "1e-9").is_ok());
}

/// Every estimator that starts from a prior refuses an extreme one at build time with the
/// parameter named, not with an internal bound name (`lower` … must be below `upper`) or a
/// divergence at the first samples.
#[test]
fn errors_the_builder_refuses_an_extreme_prior_by_name() {
    // The sliding-mode engines are large stack values in a debug build.
    std::thread::Builder::new()
        .stack_size(64 << 20)
        .spawn(builder_refuses)
        .unwrap()
        .join()
        .unwrap();
}

fn builder_refuses() {
    let st = ModelStructure::longitudinal();
    let i = st.names().position(|n| n == "Cm_alpha").unwrap();
    for (value, sigma) in [(-0.5, 1e10), (-0.5, 1e-17), (-1e300, 1.0), (-0.5, f64::INFINITY)] {
        let mut priors = Priors::generic(&st);
        priors.prior[i] = ParamPrior { value, sigma };
        for kind in [
            EstimatorKind::Ekf,
            EstimatorKind::Smpe,
            EstimatorKind::SmpeCorrected,
            EstimatorKind::Gradient,
            EstimatorKind::Rls,
        ] {
            let e = match build(kind, st, priors, &EstimatorOptions::default()) {
                Err(e) => e,
                Ok(_) => panic!("{}: prior {value} ± {sigma} accepted", kind.name()),
            };
            assert!(matches!(e, BuildError::Prior { .. }), "{e}");
            let text = e.to_string();
            assert!(text.contains("prior of `Cm_alpha`"), "{text}");
            assert!(text.contains(&format!("sigma {sigma}")), "{text}");
            assert!(!text.contains("`lower`"), "{text}");
        }
    }
    let ok = build(EstimatorKind::Smpe, st, Priors::generic(&st), &EstimatorOptions::default());
    assert!(ok.is_ok());
}
