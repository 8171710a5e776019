//! Integration tests of the Ductile workspace live in `tests/`; this library holds what
//! they share with the fuzzers under `fuzz/`: the fuzz targets ([`fuzz`]).

pub mod fuzz;
