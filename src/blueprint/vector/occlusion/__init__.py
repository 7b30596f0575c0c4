"""Occlusion level of lines against peeled depth layers.

Each polyline is sampled along its screen projection about a pixel apart, its own vertices
always among the samples (``samples``). A sample's level is the number of peeled surfaces in
front of it, found from the planes of the layers' triangles on the sample's own view ray, the
minimum over the 2 x 2 pixels whose centres surround it (``levels``); a peel keeps its layers'
triangle IDs only at the pixels those tests look at (``pixels``).

Two more passes clean what pixels cannot tell: :func:`verify_creases` drops mesh edges where
the surfaces to both sides of the line are one flat surface of one part (solids of one part
pressed together), and :func:`suppress_coincident` (``coincident``) drops stretches that lie on
a line of lower level (the bottom outline of a plate under its top outline in a plan view). A
polyline is then cut where its level changes, halfway between the two samples that differ; a
change must hold for 2.5 pixels, shorter stretches taking a neighbour's level, the shortest
first (``runs``).
"""

from .coincident import suppress_coincident
from .gpu import FacesDrawn, GpuLevels, draw_faces, gpu_levels, stack_levels
from .levels import DepthTest, classify_samples, drop_phantoms, face_planes, verify_creases
from .pixels import PixelLayers, probe_pixels
from .runs import split_by_level
from .samples import Samples, sample_polylines

__all__ = [
    "DepthTest",
    "FacesDrawn",
    "GpuLevels",
    "PixelLayers",
    "Samples",
    "classify_samples",
    "draw_faces",
    "drop_phantoms",
    "probe_pixels",
    "face_planes",
    "gpu_levels",
    "sample_polylines",
    "split_by_level",
    "stack_levels",
    "suppress_coincident",
    "verify_creases",
]
