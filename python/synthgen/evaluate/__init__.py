"""Evaluation: does a detector trained on synthgen images find the objects in real photos.

The stage above :mod:`synthgen.run` (it reads datasets and real label files; nothing below it
imports it) and below ``bench`` and ``cli``. It holds, as issue 34 builds it:

- :mod:`.score` -- scoring detections against ground truth the COCO way (AP50, AP50:95 with
  101-point interpolation, recall at 0.1 false positives per image, per class and per size
  bucket of box height, bootstrap 95% intervals over images), the plain-text table, and
  detections exported as COCO results or as ``synthgen evaluate detect`` records. Pure numpy:
  it works without PyTorch;
- :mod:`.backbone` -- the reference detector's backbone: ShuffleNetV2 0.5x in Megvii's block
  layout, its ImageNet-pretrained weights loaded by an explicit key table (checked by BatchNorm
  statistics on real photos), the input normalisation (needs PyTorch, :mod:`._torch`);
- :mod:`.targets` -- the detector's CenterNet targets (a Gaussian centre heatmap per class,
  log box size and sub-cell offset on one stride-8 grid; ignore regions masked), its losses
  (focal loss, L1), decoding (3 x 3 peaks, top-k) and class-wise NMS in plain torch;
- :mod:`.detector` -- the reference detector (the backbone, a neck onto stride 8, the CenterNet
  head), its ``detect``, and its single-file save/load (``Detector.from_file``);
- :mod:`.datasets` -- the images it trains and is scored on: synthgen datasets (the occlusion
  rule, a photo frame's real objects and ignore regions), real label sets in every format of
  :mod:`synthgen.background.label_files` (format detected, class mapping, drops counted) and
  images without objects, as :class:`.datasets.Sample` records and :mod:`.score` ground truth;
- :mod:`.augment`, :mod:`.train` -- training: augmentation, pools mixed by fixed shares per
  batch, the optimisation, the manifest saved in the model file; :func:`.train.detect_samples`;
- :mod:`.images` -- images read by synthgen's strict reader (Pillow where the core is absent);
- :mod:`.plots` -- the precision-recall figure of ``synthgen evaluate score``.

The command line is :mod:`synthgen.cli.evaluate` (``synthgen evaluate train|score|detect``).

PyTorch is optional: a module that needs it imports it lazily, inside the functions that use
it, and a missing torch raises a :class:`synthgen.SynthgenError` naming the Debian packages
``python3-torch python3-torchvision``. This file imports nothing heavy (no module of its own).
"""
