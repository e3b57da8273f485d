"""Per-model control-table facts (TOML); a package so that wheels ship the files as package data."""
