"""Real photos as backgrounds: their calibration (camera, lens, ground, sun), the labels of
what they already show, and the choice of a frame's photo.

* :mod:`.calibration` -- the :class:`~.calibration.Calibration` of a photo and the geometry
  that derives it (horizon + camera height, ground plane, marked shadow -> sun);
"""
