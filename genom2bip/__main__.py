"""``python -m genom2bip``: the same command as the ``genom2bip`` console script."""
from genom2bip.cli import main

raise SystemExit(main())
