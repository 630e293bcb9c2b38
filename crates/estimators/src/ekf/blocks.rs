//! The six-axis EKF by blocks: a longitudinal and a lateral-directional filter, each
//! integrating its own axis's states and taking the other axis's from the sample (the
//! [`StateSet`]s of the flight model), over the longitudinal and the lateral coefficients of
//! one structure.
//!
//! Why: the coupled filter's covariance is `(8 + p) × (8 + p)`, and much of its per-sample cost
//! grows with its square; two blocks of about `4 + p/2` cost 0.69 of it together on the
//! six-axis preset (`structure_estimators/ekf_six_axis_blocks_1000_samples`: the model's
//! evaluations do not shrink). What is lost is
//! what couples the axes inside the filter: the cross-covariance of the two axes' states and
//! parameters, and the noise of the other axis's measured states, which each block takes as
//! exact inputs. The blocks' estimates are each block's own, bit for bit
//! (`tests::the_blocks_are_the_two_axis_filters`); docs/six-axis.md gives the 200-run Monte
//! Carlo of the default flight, coupled against blocks.

use super::{Ekf, EkfConfig};
use crate::EstimatorError;
use crate::estimator::{Estimates, Estimator, EventLog, EventMark, Status};
use crate::flight_model::StateSet;
use crate::sample::AirDataSample;
use crate::vocabulary::{Coefficient, MAX_PARAMS, ModelStructure};

/// A longitudinal and a lateral [`Ekf`] over one coupled structure (module doc).
#[derive(Debug, Clone)]
pub struct EkfBlocks {
    structure: ModelStructure,
    /// The longitudinal block, then the lateral one.
    blocks: [Ekf; 2],
    /// Per block, the structure index of each of its parameters.
    index: [[usize; MAX_PARAMS]; 2],
    est: Estimates,
    events: EventLog,
    /// Per block, where its log stood when [`Self::events`] last took it in.
    events_seen: [EventMark; 2],
}

/// Whether coefficient `c` is lateral-directional.
fn lateral(c: Coefficient) -> bool {
    matches!(c, Coefficient::CY | Coefficient::Cl | Coefficient::Cn)
}

/// The part of `cfg` over the coefficients `keep` selects: its structure, priors and
/// parameter walks, and the structure index of each of its parameters.
fn block_config(
    cfg: &EkfConfig,
    keep: fn(Coefficient) -> bool,
) -> (EkfConfig, [usize; MAX_PARAMS]) {
    let full = cfg.structure;
    let mut structure = ModelStructure::empty().with_knots(*full.knots());
    for p in full.params().filter(|p| keep(p.coefficient)) {
        structure.insert(p);
    }
    let mut block = EkfConfig { structure, ..*cfg };
    let mut index = [0; MAX_PARAMS];
    block.priors.n = structure.n_params();
    for (b, p) in structure.params().enumerate() {
        // Every parameter of the block is one of `full`'s (the block is built from them).
        let i = full.params().position(|q| q == p).unwrap_or(0);
        index[b] = i;
        block.priors.prior[b] = cfg.priors.prior[i];
        block.param_process_noise[b] = cfg.param_process_noise[i];
    }
    (block, index)
}

impl EkfBlocks {
    /// The two blocks of `cfg`, whose structure must have both axes complete.
    ///
    /// # Errors
    /// [`EstimatorError::InvalidConfig`] when the structure is not coupled (one axis only:
    /// use [`Ekf`]), or either block's configuration error ([`Ekf::new`]).
    pub fn new(cfg: EkfConfig) -> Result<Self, EstimatorError> {
        if StateSet::of(&cfg.structure)? != StateSet::Coupled {
            return Err(EstimatorError::InvalidConfig {
                field: "blocks",
                value: cfg.structure.n_params() as f64,
                reason: "needs a structure with both axes; a one-axis structure is one block",
            });
        }
        let (lon, lon_index) = block_config(&cfg, |c| !lateral(c));
        let (lat, lat_index) = block_config(&cfg, lateral);
        Ok(Self {
            structure: cfg.structure,
            blocks: [Ekf::new(lon)?, Ekf::new(lat)?],
            index: [lon_index, lat_index],
            est: Estimates::new(cfg.structure.n_params()),
            events: EventLog::new(),
            events_seen: [EventMark::default(); 2],
        })
    }

    /// The block of `i` (0 longitudinal, 1 lateral) and `i`'s index in it.
    fn locate(&self, i: usize) -> Option<(usize, usize)> {
        (0..2).find_map(|b| {
            let n = self.blocks[b].np;
            self.index[b][..n].iter().position(|&j| j == i).map(|k| (b, k))
        })
    }

    /// The blocks' estimates in structure order; the status the worse of the two.
    fn publish(&mut self, t_s: f64) {
        self.est.t_s = t_s;
        for (block, index) in self.blocks.iter().zip(&self.index) {
            let e = block.estimates();
            for (k, &i) in index[..block.np].iter().enumerate() {
                self.est.set(i, e.raw_value(k), e.sigma(k), e.is_identified(k));
            }
        }
        let status = |b: &Ekf| b.estimates().status;
        self.est.status = match (status(&self.blocks[0]), status(&self.blocks[1])) {
            (Status::Diverged, _) | (_, Status::Diverged) => Status::Diverged,
            (Status::Running, Status::Running) => Status::Running,
            _ => Status::Initialising,
        };
    }

    /// The blocks' events not yet taken in, in block order, every one counted.
    fn gather_events(&mut self) {
        for (block, seen) in self.blocks.iter().zip(&mut self.events_seen) {
            self.events.absorb(&block.events, *seen);
            *seen = block.events.mark();
        }
    }
}

impl Estimator for EkfBlocks {
    fn method(&self) -> &'static str {
        "ekf"
    }

    fn structure(&self) -> &ModelStructure {
        &self.structure
    }

    /// Both blocks take the sample; a sample either block cannot read (a channel missing) is
    /// refused before either changes.
    fn update(&mut self, s: &AirDataSample) -> Result<&Estimates, EstimatorError> {
        for block in &self.blocks {
            block.model.inputs(s)?;
        }
        let updated = self.blocks.iter_mut().try_for_each(|b| b.update(s).map(|_| ()));
        self.publish(s.t_s);
        self.gather_events();
        updated.map(|()| &self.est)
    }

    fn estimates(&self) -> &Estimates {
        &self.est
    }

    /// The mean NIS over both blocks' accepted innovations.
    fn nis(&self) -> Option<f64> {
        let count: u64 = self.blocks.iter().map(|b| b.nis_count).sum();
        let sum: f64 = self.blocks.iter().map(|b| b.nis_sum).sum();
        (count > 0).then(|| sum / count as f64)
    }

    /// Within a block, the block's covariance; `None` across the axes (independent blocks).
    fn covariance(&self, i: usize, j: usize) -> Option<f64> {
        let ((bi, ki), (bj, kj)) = (self.locate(i)?, self.locate(j)?);
        (bi == bj).then(|| self.blocks[bi].covariance(ki, kj)).flatten()
    }

    fn events(&self) -> &EventLog {
        &self.events
    }

    fn new_manoeuvre(&mut self) {
        for b in &mut self.blocks {
            b.new_manoeuvre();
        }
    }
}
