"""Where the tests find other projects' data: the shared folder, read in place.

The repository keeps no copy of another project's recordings (docs/DECISIONS.md, "Other projects'
data is read in place"); they sit in `../shared/data/` beside the repository: camodocal's pose pairs,
ethz-asl's streams, the peers' sets converted by `testdata/peers/make_peers.py`, ... One rule, here
for Python (crates/handeye-py/tests/conftest.py, testdata/golden/record.py) and in
crates/handeye/tests/shared_data/mod.rs for every Rust test:

- the folder is $HANDEYE_SHARED_DATA when set (a relative value is taken from the repository's
  root), else <repository root>/../shared/data;
- a set that is not there skips what needs it, with one line saying what and why; with
  HANDEYE_SHARED_REQUIRED=1 (CI, .ci/run) it is a failure instead.

Python 3 standard library only.
"""

import os

#: The variable naming the shared folder.
SHARED_DATA = "HANDEYE_SHARED_DATA"
#: The variable that makes a missing set a failure rather than a skip.
SHARED_REQUIRED = "HANDEYE_SHARED_REQUIRED"
#: What stands for the shared folder in testdata/golden/commands.txt and in the recorded outputs.
PLACEHOLDER = "{shared}"

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def shared_dir():
    """The shared folder (it may not exist)."""
    value = os.environ.get(SHARED_DATA, "")
    if value:
        return os.path.normpath(os.path.join(ROOT, value))
    return os.path.join(os.path.dirname(ROOT), "shared", "data")


def required():
    """Whether a missing set fails (HANDEYE_SHARED_REQUIRED set, and not empty nor 0)."""
    return os.environ.get(SHARED_REQUIRED, "") not in ("", "0")


def missing(rel):
    """Whether `rel` (a set's folder or a file, e.g. "camodocal" or "peers/visp_eye_in_hand") is
    missing from the shared folder."""
    return not os.path.exists(os.path.join(shared_dir(), rel))


def why(what):
    """The one line that says why `what` cannot be read: it is not in the shared folder."""
    return (f"{what}: not in {shared_dir()}, the shared folder of other projects' data "
            f"({SHARED_DATA} names another place)")


def masked(text):
    """`text` with the shared folder's path written as the placeholder."""
    return text.replace(shared_dir(), PLACEHOLDER)


def unmasked(word):
    """`word` with the placeholder replaced by the shared folder's path."""
    return word.replace(PLACEHOLDER, shared_dir())
