"""Shared by the script tests: bad input gives exit status 2 and one line on stderr; a folder for
a test's files that goes when the test ends."""

import contextlib
import os
import shutil
import sys
import tempfile


@contextlib.contextmanager
def test_dir(tag):
    """A fresh folder, $TMPDIR (else /tmp)/scoopsim_<tag>_XXXXXXXX, removed when the block ends,
    passed or failed; kept, and named on stderr, with SCOOPSIM_KEEP_TEST_FILES=1 (as the C++ tests'
    ProcessTempDir in tests/cli_util.h). A failed test names what it removed."""
    d = tempfile.mkdtemp(prefix="scoopsim_%s_" % tag)
    keep = os.environ.get("SCOOPSIM_KEEP_TEST_FILES", "") not in ("", "0")
    failed = True
    try:
        yield d
        failed = False
    finally:
        if keep:
            print("test files kept in %s" % d, file=sys.stderr)
        else:
            shutil.rmtree(d, ignore_errors=True)
            if failed:
                print("test files removed from %s (SCOOPSIM_KEEP_TEST_FILES=1 keeps them)" % d,
                      file=sys.stderr)


def expect_refused(run, cases):
    """For each (args, needle) of `cases`, run(args) (a subprocess.CompletedProcess with text
    output) exits 2 with exactly one line on stderr, which contains `needle`."""
    for args, needle in cases:
        result = run(args)
        assert result.returncode == 2, "%s: exit %d, expected 2" % (args, result.returncode)
        lines = result.stderr.strip().splitlines()
        assert len(lines) == 1 and needle in lines[0], "%s: stderr %r" % (args, result.stderr)
