import sys

from capmj.replay.cli import main

sys.exit(main())
