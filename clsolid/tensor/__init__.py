"""The structure tensor of an image and the dissimilarities between tensors (Akl et al.,
"Structure tensor based synthesis of directional textures for virtual material design",
ICIP 2014, §2, eqs. 1-12): a NumPy float64 reference (:mod:`~clsolid.tensor.field`,
:mod:`~clsolid.tensor.dissimilarity`) and the same on an OpenCL device
(:mod:`~clsolid.tensor.opencl`)."""

from .dissimilarity import METRICS, dissimilarity, features, neighbourhood_dissimilarity
from .field import coherence, log_tensor, orientation, structure_tensor

__all__ = ["METRICS", "coherence", "dissimilarity", "features", "log_tensor", "neighbourhood_dissimilarity",
           "orientation", "structure_tensor"]
