"""Everything that draws: annotated frames (:mod:`.annotate`), the ground truth and runs overlay
(:mod:`.overlay`), the intermediate images of the motion stage (:mod:`.streams`), people's
outlines and heads (:mod:`.people`) and optical flow (:mod:`.flow`).

Drawing functions take a frame and typed results and return a new image (or draw in place when
asked); they never read sources or write files, which is the run layer's work.
"""
