# Writes the comparison scenes' sky: a 64x64 equal-area square map (pbrt-v4's
# layout), a smooth gradient that differs along both axes and a soft sun.
import sys, numpy as np, OpenImageIO as oiio
n = 64
y, x = np.mgrid[0:n, 0:n] + 0.5
u, v = x / n, y / n
sky = np.stack([0.3 + 0.9 * u, 0.4 + 0.6 * v, 0.8 + 0.4 * u * v], axis=-1)
su, sv = 0.59, 0.62  # the sun's texel centre: up and toward +x, +y
d2 = ((u - su) ** 2 + (v - sv) ** 2) * n * n
sun = 120.0 * np.exp(-d2 / (2 * 1.5 ** 2))
img = (sky + sun[..., None] * np.array([1.0, 0.9, 0.75])).astype(np.float32)
spec = oiio.ImageSpec(n, n, 3, "half")
spec.attribute("compression", "zip")
out = oiio.ImageOutput.create(sys.argv[1])
out.open(sys.argv[1], spec)
out.write_image(img)
out.close()
