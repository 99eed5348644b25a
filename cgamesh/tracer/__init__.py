"""The reference CGA ray tracer (paper sections 3, 4, 5.1, 7 and 9).

It renders a scene's analytic surfaces (found by root finding on the interpolated objects,
never from a mesh) and its spheres, planes and discs with Blinn-Phong lighting, and it is
the independent referee of the mesher: ``cgamesh verify`` compares a mesh's vertices and
normals with the traced surface. So this package never imports ``cgamesh.meshing.normals``,
``cgamesh.meshing.circles`` or ``cgamesh.meshing.ribbons``; it uses only the algebra, the control objects,
the curves and the projection.

Everything is vectorised over rays: a batch of rays is a ``Rays`` value holding CGA lines
(N, 32); Python loops run over objects, lights, reflection depth and root-finder samples.

    camera.py          pinhole camera, rays X0 ^ P ^ n_inf for every pixel (eq. 2)
    cga.py             meets (eq. 3), point pairs (eq. 5), spheres (eq. 6), lines, planes
    rays.py            batches of rays as normalised lines with their origins
    primitives.py      spheres, planes, discs, facets: hits by meets, reflections (eqs. 7-8)
    bounds.py          bounding spheres by the two-sphere algorithm (section 5.1.1)
    chebyshev.py       batched polynomial roots: Chebyshev fit, colleague matrix eigenvalues
    sampled.py         the sampled root finder (section 5.1.1) with grazing-root detection
    roots.py           intersection functions, polynomials (eqs. 16, 31) and roots per segment
    evolved.py         evolved surfaces as traceable objects: culling, hit points, caps
    surface_normals.py analytic normals (eqs. 17-25) and a numerical second opinion
    shading.py         Blinn-Phong (eqs. 34-36), attenuation, shadows, reflections
    world.py           scene specs -> traceable objects, lights, camera
    render.py          whole images, in row bands, with progress
    png.py             8-bit RGB PNG writing and reading (zlib + struct)
    meshfile.py        meshes read back from a GLB, in the scene file's frame
    raster.py          meshes drawn with the camera (for ``verify --image``)
    verify.py          mesh-versus-tracer statistics
"""
