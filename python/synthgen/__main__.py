"""``python -m synthgen``: the same as the ``synthgen`` command."""
import sys

from .cli import main

sys.exit(main())
