"""One configuration analysed: the unified Jacobian, the reduced dynamics and the measures, with
their plausibility warnings."""

from .single import Analysis, analyze, default_object

__all__ = ["Analysis", "analyze", "default_object"]
