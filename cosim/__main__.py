"""`python -m cosim`: the command line (cosim.cli)."""

from .cli import main_exit

if __name__ == "__main__":
    main_exit()
