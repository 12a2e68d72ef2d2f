"""`python -m mavswarm` runs the `mavswarm` command."""

import sys

from mavswarm.cli import main

sys.exit(main())
