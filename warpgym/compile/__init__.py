"""Compile-time acceleration: every kernel module a step needs compiled side by side before the first
step (``preload``), Warp's libmathdx objects built in child processes (``mathdx``), and a log of what
was compiled and where the time went (``log``). The only code in warpgym that touches Warp's private
build and codegen functions, pinned to warp-lang 1.19 and tested against Warp's own path."""
