from jaxrender.cli import main

raise SystemExit(main())
