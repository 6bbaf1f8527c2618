"""Pictures of the analysis: matplotlib figures (:mod:`.figures`) and the meshcat scene."""
