//! CPU mirrors of the GPU samplers and tables, for tests and self-checks.

pub mod cubemap;
pub mod distribution;
pub mod environment;
pub mod light_bvh;
pub mod luminaire;
pub mod pcg;
pub mod restricted;
pub mod scan;
