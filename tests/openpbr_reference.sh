#!/usr/bin/env bash
# tests/openpbr_reference.txt holds what tests/openpbr_reference.py (an independent numpy implementation of the
# OpenPBR equations openpbr.c follows) writes; test_brdf's known_openpbr_reference compares the model with it to
# 1e-6. The check that the file is still what the script writes: tests/lib/reference_file.sh.
exec "$(dirname "$0")/lib/reference_file.sh" openpbr_reference
