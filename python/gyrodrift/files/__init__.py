"""Safe file input and output: atomic outputs under a manifest, bounded reads of user files, TOML reading,
validation and writing."""
