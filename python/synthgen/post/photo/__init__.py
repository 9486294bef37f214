"""Inserting renders into real photos: image-space steps in linear light, each a pure function
(arrays + parameters -> arrays).

* :mod:`.composite` -- differential-rendering composites of a render with catchers into a photo
  (ratio and additive modes).
"""
