"""``python -m kinprop``: the command-line interface."""

from kinprop.cli import main

if __name__ == "__main__":
    main()
