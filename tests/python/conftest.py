"""The suite runs against the build tree: python/ on sys.path, the library of MR_BUILD (scripts/run-tests.sh sets it;
default build/), the CLI beside it for cross-checks, the shared assets of MR_SHARED (default ../shared)."""
import os
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
BUILD = os.environ.get("MR_BUILD", os.path.join(ROOT, "build"))
SHARED = os.environ.get("MR_SHARED", os.path.join(ROOT, "..", "shared"))
os.environ.setdefault("MATREMAP_LIBRARY", os.path.join(BUILD, "lib", "libmatremap.so.0"))
sys.path.insert(0, os.path.join(ROOT, "python"))
