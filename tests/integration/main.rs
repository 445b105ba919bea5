//! Integration tests of the whole toolkit, the CLI included: one binary, one
//! module per command, and one per concern the commands share.

mod acceptance;
mod arm_checks;
mod beyond;
mod builds;
mod calibrate;
mod campaign;
mod chains;
mod edges;
mod evaluate;
mod export;
mod first_cause;
mod frame_uncertainty;
mod house;
mod import;
mod mukca;
mod orientations;
mod out_paths;
mod plan;
mod plan_cli;
mod points;
mod positions;
mod prior;
mod readme;
mod real_robots;
mod report;
mod robust;
mod session;
mod sim_messages;
mod simulate;
mod sphere_term;
mod spheres;
mod streams;
mod tools;
mod util;
mod verdict;
