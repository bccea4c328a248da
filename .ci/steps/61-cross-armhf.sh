#!/usr/bin/env bash
# The armhf (32-bit ARM, NEON) cross-build: .ci/cross-build.sh.
exec bash .ci/cross-build.sh armhf
