"""Texture units, each owned by one job: a unit is global GL state, so two passes of one frame
that bound the same unit for different things would read each other's textures."""

PEEL_DEPTH = 0  # and 1: the two depth textures the peel alternates, held through the peel loop
SELECTED = 2  # part flags of a capture of chosen parts (render.capture)
KBUFFER = 3  # the k-buffer surface being unpacked into the G-buffer (render.capture)
CORNERS = 4  # face corners of triangle-ID silhouettes (the edges operation)
INPUTS = 5  # a pass's inputs, from here up (pipeline executor, compositor)
# faces whose outline the contour lines draw (the edges operation), above the inputs and the
# k-buffer's surfaces that an edges pass binds
CONTOURED = 14
# GPU silhouettes (gpu_silhouettes) are frames of their own, never interleaved with pipeline
# passes: their ID buffer and then their tables take the corner and input units
SILHOUETTE_IDS = CORNERS
