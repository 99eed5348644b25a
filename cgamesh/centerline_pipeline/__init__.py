"""Moved to cgamesh.pipelines.centerlines: this alias (the same module under its old name) warns, and goes
in the next release."""

import sys
import warnings

from cgamesh.pipelines import centerlines

warnings.warn("cgamesh.centerline_pipeline moved to cgamesh.pipelines.centerlines; import it from there (the old name goes in the "
              "next release)", FutureWarning, stacklevel=2)
sys.modules[__name__] = centerlines
