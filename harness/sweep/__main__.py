"""python -m harness.sweep SPEC --out DIR: the sweep command on its own."""
import sys

from .run import main

sys.exit(main())
