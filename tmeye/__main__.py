from tmeye.cli import main

raise SystemExit(main())
