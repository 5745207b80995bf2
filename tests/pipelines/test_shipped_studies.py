"""Every study file shipped in studies/ loads: its model, parameters and values are valid."""

from __future__ import annotations

from pathlib import Path

import pytest

from pipelines.studyfile import load_study

STUDIES = sorted((Path(__file__).resolve().parents[2] / "studies").glob("*.toml"))


@pytest.mark.parametrize("path", STUDIES, ids=[p.name for p in STUDIES])
def test_shipped_study_loads(path):
    study = load_study(path)
    assert len(study.cases) >= 1


def test_the_shipped_studies_are_found():
    assert len(STUDIES) >= 6
