//! The C ABI: the only unsafe code in the crate.
