"""``python -m expressive_mocap.cli``: the ``expressive-mocap`` command."""

import sys

from . import main

sys.exit(main())
