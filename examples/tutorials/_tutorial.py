"""What the tutorial scripts share: their command line and how they save a figure."""
import argparse
from pathlib import Path


def save_figure(fig, out, name):
    """Save ``fig`` as the PNG ``out/name`` (creating ``out``), close it and say where it went."""
    import matplotlib.pyplot as plt
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    fig.tight_layout()
    fig.savefig(out / name, dpi=110)
    plt.close(fig)
    print(f"wrote {out / name}")


def main(run, doc, plots=True):
    """A tutorial's command line: ``--out DIR`` (and ``--no-plot`` if it plots), then ``run(...)``."""
    parser = argparse.ArgumentParser(description=doc.splitlines()[0])
    parser.add_argument("--out", default="results/tutorials", help="where figures and files go")
    if plots:
        parser.add_argument("--no-plot", action="store_true", help="skip the figures")
    args = parser.parse_args()
    if plots:
        run(out=args.out, plot=not args.no_plot)
    else:
        run(out=args.out)
