"""``python -m lcpbench.cli``: the same as the ``lcpbench`` command."""

from . import main

raise SystemExit(main())
