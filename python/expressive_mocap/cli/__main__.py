"""``python -m expressive_mocap.cli``: the ``expressive-mocap`` command."""

import sys

from . import main

__all__: list[str] = []

sys.exit(main())
