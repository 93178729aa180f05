"""From captured motion to rig controls (Chen et al. 2012, Appendix A) and its relatives.

- :mod:`~dam.crossmap.rig`: rigs (linear blendshape or any callable) and shared checks.
- :mod:`~dam.crossmap.crossmapping`: key shapes by affinity propagation, NNLS blend weights,
  bounded control fit (:class:`CrossMapper`).
- :mod:`~dam.crossmap.retarget`: rig-space retargeting (Taylor et al. 2017, Eqs. 2-3).
- :mod:`~dam.crossmap.landmarks`: landmark-to-rig solve (Medina et al. 2022, Eqs. 2-4).
- :mod:`~dam.crossmap.outlines`: VocalTractLab midsagittal outlines as captured points.
"""

from __future__ import annotations

from dam._lazy import lazy_exports

_EXPORTS = {
    **dict.fromkeys(["LinearRig", "as_rig", "load_matrix"], ".rig"),
    **dict.fromkeys(
        ["CrossMapper", "find_key_shapes", "blend_weights", "blend_vertices", "fit_controls"], ".crossmapping"
    ),
    **dict.fromkeys(
        [
            "RigSpaceRetargeter",
            "principal_modes",
            "project",
            "retargeting_poses",
            "retarget_weights",
            "rig_space_retarget",
        ],
        ".retarget",
    ),
    **dict.fromkeys(
        ["LandmarkSolver", "solve_landmarks", "landmark_targets", "similarity_transform", "tied_parameters"],
        ".landmarks",
    ),
    **dict.fromkeys(
        [
            "outline_corpus",
            "tract_outlines",
            "toy_tract_rig",
            "plot_outline",
            "vtl_shape",
            "resample_contour",
            "outline_channels",
            "CONTOURS",
        ],
        ".outlines",
    ),
}
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS, ("rig", "crossmapping", "retarget", "landmarks", "outlines"))

__all__ = list(_EXPORTS)
