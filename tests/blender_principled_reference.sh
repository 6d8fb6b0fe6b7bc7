#!/usr/bin/env bash
# tests/blender_principled_reference.txt holds what tests/blender_principled_reference.py (a numpy
# implementation of Cycles' Principled BSDF, written from the Blender 4.2 sources and blender_principled.c's
# documented substitutions) writes; test_brdf's known_blender_principled_reference compares the model with it to
# 1e-6. The check that the file is still what the script writes: tests/lib/reference_file.sh.
exec "$(dirname "$0")/lib/reference_file.sh" blender_principled_reference
