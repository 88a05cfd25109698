"""``python -m amigo_gym.tools.cli``: the ``amigo-gym`` command."""

from amigo_gym.tools.cli import main

raise SystemExit(main())
