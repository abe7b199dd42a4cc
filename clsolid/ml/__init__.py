"""The NP-MRF maximum-likelihood method (Urs, Da Costa & Germain, TIP 2014): parameters,
per-scale model, multi-scale driver, label-histogram balance, and the OpenCL and NumPy
float64 back ends side by side."""

from ..core.probe import register_smoke_test

register_smoke_test("clsolid.ml.smoke:smoke_test")
