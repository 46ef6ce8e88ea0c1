"""Shared by the script tests: bad input gives exit status 2 and one line on stderr."""


def expect_refused(run, cases):
    """For each (args, needle) of `cases`, run(args) (a subprocess.CompletedProcess with text
    output) exits 2 with exactly one line on stderr, which contains `needle`."""
    for args, needle in cases:
        result = run(args)
        assert result.returncode == 2, "%s: exit %d, expected 2" % (args, result.returncode)
        lines = result.stderr.strip().splitlines()
        assert len(lines) == 1 and needle in lines[0], "%s: stderr %r" % (args, result.stderr)
