//! The instrumental-variable estimator compiled as a dependency (as the CLI and the pipelines
//! use it), where a miscompile of RLS's constructor once showed (docs/reliability.md).

use aeroident_estimators::{Estimator, IvConfig, ModelStructure, RlsIv};

/// Built for each preset, the estimator keeps its structure and identifies nothing before
/// data (the construction is in place, as RLS's).
#[test]
fn rls_iv_keeps_its_structure_after_construction() {
    for st in
        [ModelStructure::longitudinal(), ModelStructure::lateral(), ModelStructure::six_axis()]
    {
        let cfg = IvConfig { forgetting: 0.995, init_samples: 0, delay_samples: 7 };
        let iv = RlsIv::new(st, cfg).unwrap();
        assert_eq!(*iv.structure(), st);
        let n = st.n_params();
        assert_eq!(iv.structure().n_params(), n);
        assert!((0..n).all(|i| iv.estimates().value(i).is_none()));
    }
}
