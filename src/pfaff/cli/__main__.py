"""``python -m pfaff.cli``: the same as the ``pfaff`` command."""

import sys

from pfaff.cli.main import main

sys.exit(main())
