"""The underwater scene simulator: exact ground truth for tests and benchmarks."""

from .simulate import *  # noqa: F401,F403
from .simulate import __all__  # noqa: F401
