from capmj.generate.cli import main

raise SystemExit(main())
