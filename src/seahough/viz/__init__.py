"""Pictures of results: they draw what they are given and never run the pipeline."""

from .plot import *  # noqa: F401,F403
from .plot import __all__  # noqa: F401
