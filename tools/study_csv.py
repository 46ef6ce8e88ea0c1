"""Reading the CSV files the studies write ('#' note lines, a header, rows of numbers), shared by
the plotting scripts (tools/plot_balovnev.py, tools/plot_size_study.py); also the study's own
particle-size verdict, which tools/report.py shows too. Errors are ValueError with one line
naming the file, for the caller to print and exit 2."""
import numpy as np

# The reference study's largest converged snow particle (section 4, Fig. 6, eq. 7), which the
# particle-size plot and the report set ours beside.
STUDY_SIZE_MM = 3.5


def read(path, columns, min_rows=1):
    """(notes, data): the '#' lines without their '#', and a dict of the columns (numpy arrays)
    of a CSV whose header is exactly `columns` and which has at least `min_rows` rows."""
    try:
        with open(path) as f:
            lines = f.read().splitlines()
    except OSError as e:
        raise ValueError("%s: cannot read: %s" % (path, e.strerror))
    notes = [l[1:].strip() for l in lines if l.startswith("#")]
    body = [l for l in lines if l and not l.startswith("#")]
    if not body or tuple(body[0].split(",")) != tuple(columns):
        raise ValueError("%s: expected the header %s" % (path, ",".join(columns)))
    try:
        data = np.array([[float(v) for v in l.split(",")] for l in body[1:]], dtype=float)
    except ValueError:
        raise ValueError("%s: expected numbers in every row" % path)
    if data.ndim != 2 or data.shape[0] < min_rows or data.shape[1] != len(columns):
        raise ValueError("%s: expected at least %d row%s of %d columns" %
                         (path, min_rows, "" if min_rows == 1 else "s", len(columns)))
    return notes, {c: data[:, k] for k, c in enumerate(columns)}
