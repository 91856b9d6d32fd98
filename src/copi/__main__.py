"""``python -m copi``: the ``copi`` command."""

from copi.cli.main import main

if __name__ == "__main__":
    main()
