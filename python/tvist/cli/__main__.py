"""``python -m tvist.cli``: the ``tvist`` command."""

import sys

from tvist.cli import main

sys.exit(main())
