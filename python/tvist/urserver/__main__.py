"""``python -m tvist.urserver``: ``tvist twin-server`` with a lighter start."""

import sys

from tvist.cli.twin_server import main

sys.exit(main())
