//! Generic tests run for both dimensions.
