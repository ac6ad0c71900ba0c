#!/usr/bin/env bash
# Every test: Rust (`cargo test --workspace`) and Python (the `pacs` package's pytest suite,
# built into a venv under the target directory). What CI runs, besides fmt, clippy and Kani.
set -euo pipefail
cd "$(dirname "$0")"
cargo test --workspace
bash python/test.sh
