"""Moved to cgamesh.pipelines.scene: this alias (the same module under its old name) warns, and goes
in the next release."""

import sys
import warnings

from cgamesh.pipelines import scene

warnings.warn("cgamesh.pipeline moved to cgamesh.pipelines.scene; import it from there (the old name goes in the "
              "next release)", FutureWarning, stacklevel=2)
sys.modules[__name__] = scene
