//! The online calibrator on the pixels ([`OnlinePixels`]): the pipeline on the pixels, run on a
//! doubling schedule over a stream's records.

mod online;
pub use online::OnlinePixels;
