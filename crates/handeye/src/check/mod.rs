//! The checks that judge an X: how the poses are read, which poses disagree, how well X is
//! determined (bootstrap), how well held-out poses are predicted, and the motions' quality.

pub mod holdout;
pub mod identification;
pub mod order;
pub mod outliers;
pub mod precision;
pub mod quality;
pub mod readings;
pub mod stream;
pub mod systematic;
pub mod uncertainty;
pub mod units;
