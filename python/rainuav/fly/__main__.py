"""``python -m rainuav.fly``: the command ([`rainuav.fly.main()`][rainuav.fly.main])."""

import sys

from rainuav.fly import main

sys.exit(main())
