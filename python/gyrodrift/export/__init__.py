"""The drift model on the navigation computer: generated C99 and no_std Rust, bit-identical to Python."""
