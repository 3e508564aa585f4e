"""Process plumbing shared by every layer that runs work: memory estimates before large
allocations and the C heap's handling of freed arrays. Not maths (``core/``), so it lives
apart, at the bottom of the layers: it imports nothing of probecommit."""
