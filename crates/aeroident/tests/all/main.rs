//! The command line's integration tests: one test binary, each file of this directory a module
//! of it (a file of its own under `tests/` would be a binary of its own, compiled and linked
//! separately). A new test file is added here with `mod <name>;`; helpers shared by the modules
//! are in `common/`. Most modules run the `aeroident` binary cargo builds for the tests
//! (`CARGO_BIN_EXE_aeroident`); nextest runs each test in a process of its own.

mod common;

mod actuator_states;
mod aircraft;
mod cli_bad_input;
mod cli_exit;
mod cli_freqresp;
mod cli_freqresp_sysid;
mod cli_inspect;
#[cfg(unix)]
mod cli_interrupt;
mod cli_linearize;
mod cli_live;
mod cli_live_cross_check;
mod cli_live_latency;
mod cli_montecarlo;
mod cli_outputs;
mod cli_reader_report;
mod cli_replay;
mod cli_sim;
mod compat_ahrs_lag;
mod compat_consistency;
mod compat_degraded;
mod compat_gyro_shift;
mod compat_report;
mod compat_windows;
mod cross_check;
mod ekf_campaign_runs;
mod export_jsbsim;
mod fdoe;
mod fem_campaign;
mod fuzz_scenarios;
mod input_design;
mod input_shift;
mod inspect_whole_flight;
mod iv_noisy_regressors;
mod log_formats;
mod matched_truth;
mod mavlink_loopback;
mod oe_campaign;
mod one_binary;
mod one_road;
mod poc;
mod prior_limits;
mod record_windows;
mod replay_records;
mod replay_rejections;
mod report_html;
mod sample_timing;
mod sign_tests;
mod sim_replay;
mod small_stack;
mod spike_screen;
mod structure_selection;
mod uav_oat_mapping;
mod unmeasured_states;
mod validate_windows;
mod validation_records;
