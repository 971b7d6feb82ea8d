//! Light-field luminaires (Lu 14 Chapter 4, issue 9; in progress): the GPU sampling tables.
//! The method itself (`lightfield`: restricted windows, A_m from the summed-area table, K_m,
//! restricted-CDF sampling, Eq. 4.18) follows src/sampling/luminaire.rs, its f64 mirror.

pub mod tables;
