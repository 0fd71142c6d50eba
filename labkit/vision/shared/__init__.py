"""What both vision pipelines use: frame sources, image sizes, exposure, the pattern curves and
the verdict."""
