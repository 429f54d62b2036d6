"""The people stage of the pipeline: heads, HOG and active shapes, one call per frame (see
:mod:`motiontrack.people` and ``docs/people.md``)."""

from __future__ import annotations

import logging
from typing import Any, Sequence

import numpy as np

from ..config import PeopleConfig
from ..tracking.association import assign, association_cost
from ..types import Box, PeopleFrame, Region
from .heads import split_regions_by_heads
from .hog import HOGParams, HOGPeopleDetector
from .shape_model import ShapeModel, load_default_model
from .shape_tracker import ShapeTracker, ShapeTrackerParams

log = logging.getLogger(__name__)

__all__ = ["PeopleStage", "head_params"]


def head_params(c: PeopleConfig) -> dict[str, float]:
    """The head detector's keyword arguments from the people settings."""
    return {"min_width": c.head_min_width, "max_width": c.head_max_width,
            "tolerance": c.head_tolerance, "min_drop": c.head_min_drop}


class PeopleStage:
    """Per-frame people processing for the pipeline (see the module docstring).

    Parameters
    ----------
    cfg : PeopleConfig
    """

    def __init__(self, cfg: PeopleConfig | None = None) -> None:
        self.cfg = cfg or PeopleConfig()
        c = self.cfg
        self.shape_tracker = None
        if c.shapes:
            model = ShapeModel.load(c.shape_model) if c.shape_model else load_default_model()
            self.shape_tracker = ShapeTracker(model, ShapeTrackerParams(
                samples=c.samples, search=c.search, edge_threshold=c.edge_threshold,
                iterations=c.iterations, min_support=c.min_support, max_coast=c.max_coast))
        self.hog = None
        if c.hog != "off":
            self.hog = HOGPeopleDetector(HOGParams(upscale=c.hog_upscale, hit_threshold=c.hog_threshold))
        self._frame = 0
        self._hyp_active: set[int] = set()
        self._hog_cache: list[Region] = []

    def reset(self) -> None:
        """Forget the people followed so far (after a discontinuity of the source)."""
        if self.shape_tracker is not None:
            self.shape_tracker.reset()
        self._hyp_active = set()
        self._hog_cache = []

    @property
    def needs_background(self) -> bool:
        """Whether :meth:`process` reads the motion detector's background image of the frame
        (the shape tracker fits outlines to the edges of frame − background)."""
        return self.shape_tracker is not None

    def split_regions(self, mask: np.ndarray | None, regions: Sequence[Region], width: int
                      ) -> tuple[list[Region], list[Any]]:
        """Step 1 alone: heads in each region and merged regions split between adjacent heads.

        Needs only the mask (processing resolution) and the frame ``width`` (original pixels), not
        the background or the tracks. Returns ``(regions, heads)``; regions are unchanged when
        heads are off or there is no mask (external detections)."""
        c = self.cfg
        if not c.heads or mask is None:
            return list(regions), []
        return split_regions_by_heads(mask, list(regions), mask.shape[1] / width, split=c.split,
                                      **head_params(c))

    def process(self, frame_img: np.ndarray, background: np.ndarray | None, mask: np.ndarray | None,
                regions: Sequence[Region], tracks: Sequence[Any], work: np.ndarray | None = None
                ) -> tuple[list[Region], PeopleFrame]:
        """One frame.

        Parameters
        ----------
        frame_img : (H, W[, 3]) uint8
            The original frame.
        background : (h, w[, 3]) uint8 or None
            The motion detector's background estimate (processing resolution is fine).
        mask : (h, w) uint8 or None
            Cleaned motion mask at processing resolution (None with external detections: heads
            and splitting are then skipped).
        regions : sequence of Region
            Motion regions, original pixels.
        tracks : sequence of Track
            The region tracker's tracks from the previous frame.
        work : (h, w[, 3]) uint8, optional
            The preprocessed frame the motion detector saw (same size as ``background``); pass it,
            otherwise the shape tracker approximates the default preprocessing.

        Returns
        -------
        regions_out : list of Region
            Regions for the region tracker.
        found : PeopleFrame
            Heads, fitted shapes, HOG detections, the hypotheses for lost people (when
            ``hypotheses`` is on, for drawing), the fitted box of every tracked person no region
            covers by track id (whatever ``hypotheses`` says — for a region tracker that can
            apply a hypothesis to that one track without ever starting a new track from it), and
            the fitted outlines' boxes by track id (``shape_split``).
        """
        H, W = frame_img.shape[:2]
        regions = list(regions)
        found: dict[str, Any] = {}
        # 1. heads, and splitting merged regions between them.
        out, found["heads"] = self.split_regions(mask, regions, W)
        # 2. HOG, alone or inside motion regions.
        if self.hog is not None:
            out = self._hog(frame_img, regions, out, found)
        # 3. shapes, and hypotheses for people no region covers.
        if self.shape_tracker is not None:
            out = self._shapes(frame_img, background, mask, work, out, tracks, found)
        self._frame += 1
        found["heads"] = tuple(found["heads"])
        return out, PeopleFrame(**found)

    def _hog(self, frame_img: np.ndarray, regions: list[Region], out: list[Region],
             found: dict[str, Any]) -> list[Region]:
        """Step 2: HOG people, detected every ``hog_every`` frames, replace all regions
        (``hog="alone"``: the last detections are reused in between, they are all there is) or
        the motion regions holding their centres (``hog="regions"``: only on the frames HOG ran;
        in between the frame's own motion regions stand, as boxes detected frames ago would put
        moving people where they were, not where they are)."""
        c = self.cfg
        fresh = self._frame % c.hog_every == 0
        if fresh:
            self._hog_cache = (self.hog.detect(frame_img) if c.hog == "alone"
                               else self.hog.detect_in_regions(frame_img, regions))
        if c.hog == "alone":
            found["hog"] = tuple(self._hog_cache)
            return list(self._hog_cache)
        if not fresh:
            return out
        found["hog"] = tuple(self._hog_cache)
        return _replace_with_detections(out, self._hog_cache)

    def _shapes(self, frame_img: np.ndarray, background: np.ndarray | None,
                mask: np.ndarray | None, work: np.ndarray | None, out: list[Region],
                tracks: Sequence[Any], found: dict[str, Any]) -> list[Region]:
        """Step 3: outlines fitted to the tracked people; regions refined or extended by them,
        and hypotheses for people no region covers."""
        c = self.cfg
        H, W = frame_img.shape[:2]
        shapes = self.shape_tracker.update(frame_img, background, out, tracks,
                                           heads=found["heads"], mask=mask, work=work)
        found["shapes"] = tuple(shapes)
        if c.shape_split:
            # outlines fitted this frame, of people already compared with their track (an
            # outline never measured against its track's box is not trusted to split)
            found["located_by_track"] = {s.track_id: s.box.as_array() for s in shapes
                                          if s.coasting == 0 and s.agreement >= 0}
        if c.refine and shapes:
            out = _refine(shapes, out, c.hypothesis_iou, c.refine_support)
        if c.border_extend and shapes:
            out = _extend_at_border(shapes, out, W, H, c.border_support)
        if shapes:
            # Every tracked person no region covers, for a region tracker that can apply a
            # hypothesis to that one track (never starting a new track from it).
            found["hypotheses_by_track"] = _by_track(shapes, out, c, W, H)
        if c.hypotheses and shapes:
            found["hypotheses"] = self._hypotheses(shapes, out, W, H)
        else:
            self._hyp_active = set()
        return out

    def _hypotheses(self, shapes, regions: list[Region], W: int, H: int) -> tuple[Region, ...]:
        """Boxes of lost people no region covers (for drawing); remembers who is offered one.

        Only for people the region tracker has lost (or that were already being offered): a
        hypothesis for a reported track would compete with its own region. And only while the
        shape still finds edges: a pure prediction is not evidence.
        """
        c = self.cfg
        eligible = [s for s in shapes if (s.unseen > 0 or s.track_id in self._hyp_active)
                    and s.coasting <= c.hypothesis_coast
                    and s.agreement >= c.hypothesis_agreement]
        hyps, ids = _uncovered(eligible, shapes, regions, c.hypothesis_iou, c.hypothesis_score,
                               W, H)
        self._hyp_active = set(ids)
        return tuple(hyps)


def _replace_with_detections(regions: list[Region], dets: list[Region]) -> list[Region]:
    """Motion regions containing a detection centre are replaced by those detections."""
    if not dets:
        return regions
    centres = np.array([d.box.center for d in dets])
    used = np.zeros(len(dets), bool)
    out: list[Region] = []
    for r in regions:
        b = r.box
        inside = ((centres[:, 0] >= b.x) & (centres[:, 0] <= b.x2)
                  & (centres[:, 1] >= b.y) & (centres[:, 1] <= b.y2) & ~used)
        if inside.any():
            used |= inside
            out.extend(d for d, k in zip(dets, inside) if k)
        else:
            out.append(r)
    return out


def _by_track(shapes, regions: list[Region], c: PeopleConfig, W: int, H: int) -> dict[int, Region]:
    """``{track_id: Region}`` for every shape no region covers that found edges recently."""
    eligible = [s for s in shapes if s.coasting <= c.hypothesis_coast
                and s.agreement >= c.hypothesis_agreement]
    hyps, ids = _uncovered(eligible, shapes, regions, c.hypothesis_iou, c.hypothesis_score, W, H)
    return dict(zip(ids, hyps))


def _extend_at_border(shapes, regions: list[Region], W: int, H: int, min_support: float
                      ) -> list[Region]:
    """Regions cut off by the image border take their person's extent beyond it from the outline.

    A motion region touching the border sees only the part of a person inside the image; a fitted
    outline (a whole-body model) reaches past the border. For a region touching a border that is
    matched one-to-one (IoU >= 0.5 with the outline's box cut to the image) to a shape fitted this
    frame whose box reaches past that border, the region's box is extended on that side only, to
    the outline's edge; its other sides are kept. The shape must have found edges on at least
    ``min_support`` of its *visible* sample points (``support >= min_support * visible``): the
    part beyond the border cannot be seen, so plain support would reject every such shape.
    """
    edge = 1.0
    at_border = [i for i, r in enumerate(regions)
                 if r.box.x <= edge or r.box.y <= edge or r.box.x2 >= W - edge or r.box.y2 >= H - edge]
    good = [s for s in shapes if s.coasting == 0 and s.visible > 0
            and s.support >= min_support * s.visible]
    if not at_border or not good:
        return regions
    sb = np.array([s.box.as_array() for s in good]).reshape(-1, 4)
    cut = sb.copy()
    cut[:, 0], cut[:, 1] = np.maximum(sb[:, 0], 0), np.maximum(sb[:, 1], 0)
    cut[:, 2] = np.minimum(sb[:, 0] + sb[:, 2], W) - cut[:, 0]
    cut[:, 3] = np.minimum(sb[:, 1] + sb[:, 3], H) - cut[:, 1]
    rb = np.array([regions[i].box.as_array() for i in at_border]).reshape(-1, 4)
    matches, _, _ = assign(association_cost(cut, rb, 0.5, 0.0, "iou"))
    out = list(regions)
    for si, k in matches:
        ri = at_border[k]
        r = regions[ri]
        x1, y1, x2, y2 = r.box.x, r.box.y, r.box.x2, r.box.y2
        s = sb[si]
        if x1 <= edge and s[0] < 0:
            x1 = float(s[0])
        if y1 <= edge and s[1] < 0:
            y1 = float(s[1])
        if x2 >= W - edge and s[0] + s[2] > W:
            x2 = float(s[0] + s[2])
        if y2 >= H - edge and s[1] + s[3] > H:
            y2 = float(s[1] + s[3])
        if (x1, y1, x2, y2) != (r.box.x, r.box.y, r.box.x2, r.box.y2):
            box = Box.from_xyxy(x1, y1, x2, y2)
            out[ri] = Region(box=box, centroid=box.center, area=r.area, score=r.score)
    return out


def _refine(shapes, regions: list[Region], min_iou: float, min_support: float) -> list[Region]:
    """Regions matched one-to-one to a shape with ``support >= min_support`` take its box.

    Matching is Hungarian on IoU gated at ``min_iou``; the region keeps its score and area, its
    centroid becomes the outline box centre.
    """
    good = [s for s in shapes if s.support >= min_support and s.visible >= min_support
            and s.coasting == 0]
    if not good or not regions:
        return regions
    sb = np.array([s.box.as_array() for s in good]).reshape(-1, 4)
    rb = np.array([r.box.as_array() for r in regions]).reshape(-1, 4)
    matches, _, _ = assign(association_cost(sb, rb, min_iou, 0.0, "iou"))
    out = list(regions)
    for si, ri in matches:
        box = good[si].box
        out[ri] = Region(box=box, centroid=box.center, area=regions[ri].area, score=regions[ri].score)
    return out


def _uncovered(eligible, shapes, regions: list[Region], min_iou: float, score: float, W: int, H: int
               ) -> tuple[list[Region], list[int]]:
    """Boxes of ``eligible`` shapes that no region is assigned to, and their track ids (aligned).

    Regions are assigned to all ``shapes`` (Hungarian on IoU, gated at ``min_iou``), so a merged
    region covers one person only.
    """
    if not eligible:
        return [], []
    sb = np.array([s.box.as_array() for s in shapes]).reshape(-1, 4)
    rb = np.array([r.box.as_array() for r in regions]).reshape(-1, 4)
    cost = association_cost(sb, rb, min_iou, 0.0, "iou")  # IoU gate only
    matches, unmatched, _ = assign(cost)
    want = {s.track_id for s in eligible}
    hyps, ids = [], []
    for i in unmatched:
        if shapes[i].track_id not in want:
            continue
        x, y, w, h = (float(v) for v in sb[i])
        x1, y1 = max(0.0, x), max(0.0, y)
        x2, y2 = min(float(W), x + w), min(float(H), y + h)
        if x2 - x1 < 1 or y2 - y1 < 1:
            continue
        box = Box(x1, y1, x2 - x1, y2 - y1)
        hyps.append(Region(box=box, centroid=box.center, area=box.area, score=score))
        ids.append(shapes[i].track_id)
    return hyps, ids
