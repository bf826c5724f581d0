"""hearsee.learn: manifold learning for perception (thesis ch. 6)."""

from hearsee.learn.nle import (
    ClusteredNLE,
    DisconnectedGraphWarning,
    ManifoldInputError,
    NeighborhoodLinearEmbedding,
    adaptive_neighbors,
    make_head_pose_images,
    make_two_rolls,
    reconstruction_weights,
)

__all__ = [
    "ClusteredNLE",
    "DisconnectedGraphWarning",
    "ManifoldInputError",
    "NeighborhoodLinearEmbedding",
    "adaptive_neighbors",
    "make_head_pose_images",
    "make_two_rolls",
    "reconstruction_weights",
]
