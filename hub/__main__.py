"""`python -m hub` runs the command line."""
import sys

from hub.cli.main import main

sys.exit(main())
