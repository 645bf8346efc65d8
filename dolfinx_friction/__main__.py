from dolfinx_friction.cli import main

raise SystemExit(main())
