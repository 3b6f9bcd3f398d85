"""``python -m vgs.cli``: the ``vgs`` command."""

import sys

from vgs.cli.parser import main

sys.exit(main())
