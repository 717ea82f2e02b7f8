import sys

from capmj.bench.cli import main

# The guard matters: worker processes are started with "spawn", which re-imports this module.
if __name__ == "__main__":
    sys.exit(main())
