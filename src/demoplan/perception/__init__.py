"""Block perception from a camera above the table (paper §V.B; docs/formats.md "Camera image").

- :mod:`~demoplan.perception.camera`: pixels ↔ world, reading images;
- :mod:`~demoplan.perception.colours`: background, foreground and colour classes;
- :mod:`~demoplan.perception.hough`: the paper's Hough transform over (x, y, θ, s);
- :mod:`~demoplan.perception.blocks`: detection = colours + Hough + sub-pixel fit → a scene;
- :mod:`~demoplan.perception.stacking`: a block covered after a move is under the moved one;
  blocks of one colour (instances of one type) told apart by where they were;
- :mod:`~demoplan.perception.synthetic`: test images of blocks (anti-aliased, noisy, shaded);
- :mod:`~demoplan.perception.sequence`: a demonstration from camera frames (the hand
  ignored, a step when the picture settles); :mod:`~demoplan.perception.frames`: frames
  from image files or a video; :mod:`~demoplan.perception.filmed`: demonstrations filmed
  with a hand, for tests.
"""
