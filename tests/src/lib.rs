//! Integration tests of the Ductile workspace live in `tests/`; this library is empty.
