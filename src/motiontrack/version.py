"""The version of motiontrack, in the bottom layer: every module that records it (codec cache
keys, study and batch outputs, ``--version``) imports it from here, never from the package
root, which sits above them all."""

__version__ = "0.1.0"
