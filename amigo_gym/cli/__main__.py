"""``python -m amigo_gym.cli``: the ``amigo-gym`` command."""

from amigo_gym.cli import main

raise SystemExit(main())
