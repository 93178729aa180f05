"""``python -m dam.cli`` = ``dam``."""

import sys

from dam.cli import main

sys.exit(main())
