"""What the study plots share (tools/plot_study.py, plot_frf.py, plot_characterisation.py):
their messages and exit codes, matplotlib without a display, opening a stored study
read-only, and writing the figure."""
import sqlite3
import sys


def fail(program, message, code=2):
    print(f"{program}: {message}", file=sys.stderr)
    sys.exit(code)


def pyplot(program):
    """matplotlib's pyplot drawing into files, or exit 1 naming the package to install."""
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        fail(program, "matplotlib is missing: install Debian's python3-matplotlib (tools/setup.sh python3-matplotlib)",
             1)
    return plt


def open_study(program, db_file, study, columns="name"):
    """The store read-only and the study's `columns` row from `studies`, or exit 2."""
    db = sqlite3.connect(f"file:{db_file}?mode=ro", uri=True)
    row = db.execute(f"SELECT {columns} FROM studies WHERE study_id = ?", (study,)).fetchone()
    if row is None:
        fail(program, f"study {study} is not in {db_file} (see 'pdamp study list')")
    return db, row


def save(fig, out, study):
    """Writes the figure (default study-ID.png) and prints its name."""
    fig.tight_layout()
    out = out or f"study-{study}.png"
    fig.savefig(out, dpi=110)
    print(out)
