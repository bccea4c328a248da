#!/usr/bin/env bash
# The aarch64 (64-bit ARM) cross-build: .ci/cross-build.sh.
exec bash .ci/cross-build.sh aarch64
