"""Input and output: video sources and sinks, annotation formats, atomic files."""
