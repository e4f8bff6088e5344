//! The harness's integration tests in one binary, a module per file: the whole harness is
//! compiled into and linked with one test binary instead of twenty (each about 55 MB).

mod adversarial_scenes;
mod build_limits;
mod claims;
mod cli;
mod common;
mod compare;
mod dumps;
mod history;
mod hostile;
mod interrupt;
mod peers;
mod points;
mod registry;
mod report_browser;
mod report_pictures;
mod report_render;
mod report_sweeps;
mod results;
mod rounds;
mod run;
mod scene_cmd;
mod suite_limits;
mod verify;
