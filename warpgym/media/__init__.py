"""Pictures: drawing robots with MuJoCo's renderer (``render``), writing MP4 and GIF files (``video``),
and the clips that training and play.py record (``clips``). Needs the ``video`` extra."""
