from jaxrender.bench import main

raise SystemExit(main())
