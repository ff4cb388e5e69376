"""Where the repository's own files are, for tests that read them (README, shared/, data/)."""

from __future__ import annotations

from pathlib import Path

REPO_ROOT = Path(__file__).resolve().parents[2]
"""The checkout's root: this file is tests/support/repo.py."""
