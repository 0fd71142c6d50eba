"""The stroboscope pipeline: frames -> body -> phase -> motion fit -> checks."""
