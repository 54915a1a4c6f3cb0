"""``python -m seahough``: the same as the ``seahough`` command."""

from .cli import main

if __name__ == "__main__":  # pragma: no cover
    main()
