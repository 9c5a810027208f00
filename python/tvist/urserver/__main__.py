"""``python -m tvist.urserver``: ``tvist twin-server`` with a lighter start."""

import sys

from tvist.urserver.cli import main

sys.exit(main())
