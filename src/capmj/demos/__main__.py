import sys

from capmj.demos.cli import main

sys.exit(main())
