//! The calibration job: [`calibrate`](crate::calibrate()) runs one pipeline ([`pipeline`]) for
//! every problem ([`Problem`](crate::Problem): hand–eye, robot-world) and input kind
//! ([`Input`](crate::Input): pose pairs, the target's detections), the problems' solves in
//! `problem/` returning solutions, the one [`Report`](crate::Report) worded by the pipeline;
//! [`verify`] (the pipeline plus the comparison with a saved X) and what to record next
//! ([`advice`]).
//!
//! Each file imports only the files below it here: `input`, `options` and `low_dof` use none of
//! this folder; `report` uses `low_dof`; `reading` uses `options` and `report`; `problem/` uses
//! `options` and `low_dof`; `pipeline` uses all of those; `verify` and `pixels` (the online
//! engine on the pixels) use `pipeline`; `advice` uses `low_dof`.

pub mod advice;
pub mod input;
pub mod low_dof;
pub mod options;
pub mod pipeline;
pub mod pixels;
pub mod problem;
pub mod reading;
pub mod report;
pub mod verify;
