"""Where a likelihood run computes: the back-end options, and the back end they make.

The method's parameters (:class:`~clsolid.ml.params.MLParams`) say what is computed; the
back-end options say where and how, and never change the volume: the float64 reference,
one OpenCL device, tiles of the block on it (:mod:`clsolid.ml.tiled`), those tiles on Dask
workers (:mod:`clsolid.ml.distributed`), the state in a scratch folder on disk
(:mod:`clsolid.core.scratch`), and checkpoints (:mod:`clsolid.ml.checkpoints`).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

from ..core.hostmemory import Footprint
from ..core.options import Choice, Int, PathLike, Real, documented, option, validate
from ..core.scratch import Scratch
from ..errors import InputError

_RUN, _DEVICE = "run", "device"

#: The host memory of a likelihood run, in one piece or in tiles: the block's values,
#: temperatures and sources beside the driver's start state and the output (device buffers
#: count where the device is the host's CPU), and each term of the exemplar's windows at every
#: scale with its device copies and similar-window tables (docs/design.md#host-memory).
FOOTPRINT = Footprint(48, 56, ", keep a tiled run's state on disk (tile= and scratch=, --tile N --scratch DIR: "
                              "about 4 bytes a voxel stay in memory)")
#: The same run with its state, the result and the ``+in`` mask in a scratch folder: only
#: buffers of bounded size stay in memory (a set's indices, a tile's scores).
SCRATCH_FOOTPRINT = Footprint(4, 56)


def is_reference(device: Any) -> bool:
    """Whether *device* asks for the slow float64 NumPy back end (``"reference"``)."""
    return isinstance(device, str) and device.lower() == "reference"


@documented
@dataclass(frozen=True)
class BackendOptions:
    """How and where a likelihood run computes; none of them changes the volume.

    Each field is declared once (:func:`clsolid.core.options.option`), as the method's
    parameters are; the command line's flags come from the same declarations.
    """

    tile: int | None = option(None, "grow the block in tiles of at most N voxels on a side, each with a halo, for "
                              "blocks larger than the device holds (the same volume)", group=_RUN, check=Int(1),
                              metavar="N", none="the whole block at once")
    scratch: Path | str | None = option(None, "with tile: keep the block's state in memory-mapped files in a folder "
                                        "made in DIR (removed at the end), for blocks larger than the host's memory",
                                        group=_RUN, check=PathLike("a folder path", Path), metavar="DIR",
                                        none="in memory")
    client: Any = option(None, "with tile: run the tiles of every set on this Dask client's workers", group=_RUN,
                         flag=None, none="in this process")
    checkpoint: Path | str | None = option(None, "save the run's state in this folder after every sweep, so that a "
                                           "run can be resumed", group=_RUN, check=PathLike("a folder path", Path),
                                           metavar="DIR", none="no checkpoints")
    checkpoint_every: float = option(0.0, "seconds between checkpoints (0: after every sweep; always at the end of "
                                     "a scale)", group=_RUN, check=Real(0), metavar="SECONDS")
    vector_width: int | None = option(None, "exemplar sites per vector in the distance kernel", group=_DEVICE,
                                      check=Choice((4, 8, 16)), advanced=True,
                                      none="the widest the device's compiler handles")
    voxels_per_item: int = option(4, "voxel-views per work item (they share each exemplar load)", group=_DEVICE,
                                  check=Choice((1, 2, 4, 8)), advanced=True)
    local_size: int = option(16, "work-group size (the volume does not depend on it)", group=_DEVICE, check=Int(1),
                             advanced=True)
    max_batch: int = option(32768, "most voxels relaxed per launch (bounds a scratch buffer)", group=_DEVICE,
                            check=Int(1), advanced=True)

    def __post_init__(self) -> None:
        validate(self)
        if self.scratch is not None and self.tile is None:
            raise InputError(f"scratch={self.scratch!r} keeps a tiled run's state on disk: give tile=N too "
                             "(--tile N); a block in one piece lives on the device")
        if self.client is not None and self.tile is None:
            raise InputError("client= runs the tiles of every conflict-free set on Dask workers: give tile=N too "
                             "(--tile N), tiles large enough that their compute outweighs shipping them")

    @property
    def engine_options(self) -> dict[str, Any]:
        """The keywords of :class:`~clsolid.ml.opencl.CLBackend` (and of each Dask worker's)."""
        return {"vector_width": self.vector_width, "voxels_per_item": self.voxels_per_item,
                "local_size": self.local_size, "max_batch": self.max_batch}


def backend_options(value: BackendOptions | dict | None) -> BackendOptions:
    """*value* as :class:`BackendOptions` (a dict of its fields, or None for the defaults)."""
    if value is None:
        return BackendOptions()
    if isinstance(value, BackendOptions):
        return value
    if isinstance(value, dict):
        from ..core.options import names, refuse_unknown

        refuse_unknown(value, names(BackendOptions), "backend")
        return BackendOptions(**value)
    raise InputError(f"backend={value!r} must be a clsolid.BackendOptions, a dict of its fields, or None")


def make_backend(device: Any, options: BackendOptions) -> Any:
    """The back end of a likelihood run: the float64 reference for ``device="reference"``,
    else an OpenCL engine on the chosen device, tiled with *options*' ``tile``, its tiles on
    the workers of their Dask ``client``, its state in their ``scratch`` folder."""
    if is_reference(device):
        for name in ("tile", "client", "scratch"):
            value = getattr(options, name)
            if value is not None:
                raise InputError(f"{name}={value!r} is for OpenCL devices: the reference back end holds the whole "
                                 f"volume on the host; drop {name}")
        from .reference import ReferenceBackend

        return ReferenceBackend()
    from .tiled import LocalTiles, TiledBackend, check_edge

    store = None if options.scratch is None else Scratch(options.scratch)  # checked now; made when first used
    engine_options = options.engine_options
    if options.client is not None:
        from .distributed import DaskTiles

        check_edge(options.tile)  # before asking the workers anything
        return TiledBackend(DaskTiles(options.client, device, **engine_options), options.tile, store)
    from ..core.device import select_device
    from .opencl import CLBackend

    engine = CLBackend(select_device(device), **engine_options)
    return engine if options.tile is None else TiledBackend(LocalTiles(engine), options.tile, store)
