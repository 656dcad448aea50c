"""``python -m core.cli``: the ``ease`` command."""

import sys

from . import main

sys.exit(main())
