"""Other projects' data, read in place from the shared folder (testdata/shared_data.py: ../shared/data
beside the repository, or $HANDEYE_SHARED_DATA; the one rule the Rust tests follow too).

`shared_path(rel)` is where a set would be, for building a test's parameters; the `shared` fixture
checks that the sets a test reads are there: it skips the test with one line saying why when they
are not, or fails it with HANDEYE_SHARED_REQUIRED=1 (CI)."""
import pathlib
import sys

import pytest

REPO = pathlib.Path(__file__).resolve().parents[3]
sys.path.insert(0, str(REPO / "testdata"))

import shared_data  # noqa: E402


def shared_path(rel):
    """`rel` (e.g. "camodocal/TransformPairsInput.yml") in the shared folder, there or not."""
    return pathlib.Path(shared_data.shared_dir()) / rel


@pytest.fixture
def shared():
    """`shared(*rels)`: the paths of `rels` in the shared folder (one path for one rel); a test whose
    sets are not all there is skipped with one line naming them (failed with
    HANDEYE_SHARED_REQUIRED=1)."""

    def need(*rels):
        absent = [rel for rel in rels if shared_data.missing(rel)]
        if absent:
            why = shared_data.why(", ".join(absent))
            if shared_data.required():
                pytest.fail(f"{why}; {shared_data.SHARED_REQUIRED} is set", pytrace=False)
            pytest.skip(why)
        paths = [shared_path(rel) for rel in rels]
        return paths[0] if len(paths) == 1 else paths

    return need
