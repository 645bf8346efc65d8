from dolfinx_friction.cli.frontend import main

raise SystemExit(main())
