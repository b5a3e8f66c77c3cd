"""What the probe-2 builders share: a builder whose case edits one CSV file
of its inputs (`csv_case`), and a row repeated with one cell changed
(`repeat_row`), the shape of a table that lists one key twice.
"""
from probe_inputs_common import builder, csv_rows, write_rows


def csv_case(make, file):
    """Registers a builder whose case comes from `make(d)` (the case and its
    input directory) and whose `file` in that directory the decorated
    `edit(rows, c)` rewrites: it gets the file's rows and the case, and
    returns the rows to write back (setting c["what"] and any other key of
    the case on the way)."""
    def register(edit):
        def build(d):
            c, inputs = make(d)
            path = inputs + "/" + file
            write_rows(path, edit(csv_rows(path), c))
            return c
        build.__name__ = edit.__name__
        build.__doc__ = edit.__doc__
        return builder(build)
    return register


def repeat_row(rows, k, j, value):
    """Inserts a copy of rows[k] after it with cell j replaced by
    value(old cell); returns the copy."""
    dup = list(rows[k])
    dup[j] = value(dup[j])
    rows.insert(k + 1, dup)
    return dup
