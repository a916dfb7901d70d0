"""Half-space frictional contact (MODEL.md s.8.5): discrete model, continuum reference."""
