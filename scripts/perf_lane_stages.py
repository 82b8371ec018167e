#!/usr/bin/env python3
"""Per-stage CPU time of the lane shading from `perf record -e cpu-clock -F FREQ` runs of
`conetrace render` or `conetrace bench render` (docs/benchmarks.md, "One array per
coordinate", "The path tracer in lanes"): every sample's address
mapped to the binary's function, the function to a stage (the `simd::x86::v3`/`v4` copies by
the source lines of their code), printed as ns per camera sample.
Usage: perf_lane_stages.py BINARY FREQ CAMERA_SAMPLES_PER_RUN perf.data..."""
import bisect, collections, re, subprocess, sys

binary, freq, per_run, files = sys.argv[1], float(sys.argv[2]), float(sys.argv[3]), sys.argv[4:]
syms = []
for line in subprocess.run(["nm", "-C", "-S", "--defined-only", binary], capture_output=True, text=True).stdout.splitlines():
    parts = line.split(None, 3)
    if len(parts) == 4 and parts[2] in "tTwW":
        syms.append((int(parts[0], 16), int(parts[1], 16), parts[3]))
syms.sort()
starts = [s[0] for s in syms]

def kernel_stage(start, size):
    out = subprocess.run(["objdump", "-d", "-l", "--no-show-raw-insn", f"--start-address={start}",
                          f"--stop-address={start + size}", binary], capture_output=True, text=True).stdout
    # The path tracer's stage kernels are named by their own file, whatever shading and
    # sampler code they inline: its lights, its BSDF, the paths' arrival at their hits, and
    # the draws of its vertices' numbers (sampler code inlined into the lanes' kernel).
    for caller in ("lane_lights", "lane_bsdf", "lane_scatter", "lane_waves"):
        if f"integrator/path/{caller}.rs" in out:
            return f"integrator/path/{caller}"
    counts = collections.Counter(re.findall(r"src/(integrator/lanes/[a-z]+|integrator/camera_sample|sampler/[a-z]+|texture/[a-z_]+)\.rs", out))
    for name, _ in counts.most_common():
        if "soa" in name:
            continue
        return name
    return "?"

RULES = [
    # Our intersectors, which Embree calls for curved and height patches and spheres: traversal.
    ("our intersectors (patches, spheres)", ["scene::patch::", "PatchGeometry", "HeightPatchGeometry", "SphereGeometry",
                                             "embree::user_geometry"]),
    ("picking and ordering lanes", ["lane_waves::pick_lanes", "LanePicks::place", "lay_out_by_material", "LaneSurface"]),
    ("1 gather", ["lanes::gather"]),
    ("2 interpolate", ["lanes::interpolate", "lanes::patches", "patch_surface_point", "surface_hit", "spawn_point", "on_triangle", "on_sphere", "lat_long_frame",
                       "SurfaceLookup"]),
    ("3 footprints", ["lanes::footprints", "texture_gradients", "project_cone", "footprint::"]),
    ("4 textures (lookups and filter)", ["lanes::textures", "texture::", "surface_textures", "sample_binding", "surface_inputs", "mip"]),
    ("5 lights and shadow rays", ["lanes::lights", "path::lane_lights", "shading::lights", "sample_li", "shadow_ray", "queue_shadow",
                                  "next_event", "SceneLights", "area_lights", "environment_light", "light_selection",
                                  "spherical_triangle", "alias_table", "distribution_2d", "light_interface"]),
    ("6 BSDF", ["lanes::bsdf", "path::lane_bsdf", "brdf", "OpaqueBsdf", "metallic_roughness", "MaterialBsdf", "Bsdf",
                "microfacet", "conductor", "dielectric", "fresnel", "multiple_scattering", "continue_by_bsdf",
                "bsdf_spread_angle"]),
    ("camera rays", ["camera_sample", "sampler::", "CameraBlock", "camera::"]),
    ("7 film and integrator loop", ["lane_waves", "whitted::", "path::", "integrator::", "film::", "render_tile", "trace_wave", "Waves"]),
]
KERNEL = {"integrator/lanes/interpolate": "2 interpolate", "integrator/lanes/footprints": "3 footprints",
          "integrator/lanes/lights": "5 lights and shadow rays", "integrator/lanes/bsdf": "6 BSDF",
          "integrator/camera_sample": "camera rays",
          "integrator/path/lane_waves": "vertex samples (path lanes)",
          "integrator/path/lane_lights": "5 lights and shadow rays", "integrator/path/lane_bsdf": "6 BSDF",
          "integrator/path/lane_scatter": "7 film and integrator loop", "sampler/scramble": "camera rays", "sampler/mod": "camera rays"}
# The texture filters run inside `simd::dispatch` too (aniso::sample): any texture/ source is stage 4.
TEXTURE_STAGE = "4 textures (lookups and filter)"
kernel_cache = {}

by_name = collections.defaultdict(list)
for start, size, name in syms:
    by_name[name].append(start)
bias = None

def stage(ip, sym, offset, dso):
    global bias
    if "embree" in dso:
        return "Embree"
    if not dso.endswith(binary.split("/")[-1]):
        return "other (kernel, libc, loading)"
    name = sym
    if bias is None and len(by_name.get(sym, [])) == 1:
        bias = ip - offset - by_name[sym][0]
    if "simd::x86::v" in name and bias is not None:
        start = ip - offset - bias
        i = bisect.bisect_right(starts, start) - 1
        start, size, _ = syms[i]
        if start not in kernel_cache:
            name = kernel_stage(start, size)
            kernel_cache[start] = TEXTURE_STAGE if name.startswith("texture/") else KERNEL.get(name, "other kernel")
        return kernel_cache[start]
    for label, keys in RULES:
        if any(k in name for k in keys):
            return label
    return "other (loading, BVH build, EXR)"

totals = collections.Counter()
for f in files:
    bias = None  # each run is loaded at its own address
    out = subprocess.run(["perf", "script", "-i", f, "-F", "ip,sym,symoff,dso"], capture_output=True, text=True).stdout
    for line in out.splitlines():
        m = re.match(r"\s*([0-9a-f]+)\s+(.*?)(?:\+0x([0-9a-f]+))?\s+\((.*)\)\s*$", line)
        if not m:
            continue
        ip, sym, off, dso = int(m.group(1), 16), m.group(2), int(m.group(3) or "0", 16), m.group(4)
        totals[stage(ip, sym, off, dso)] += 1
runs = len(files)
ns = lambda n: n / freq / runs / per_run * 1e9
order = ["camera rays", "Embree", "our intersectors (patches, spheres)", "picking and ordering lanes", "1 gather", "2 interpolate", "3 footprints",
         "4 textures (lookups and filter)", "vertex samples (path lanes)", "5 lights and shadow rays", "6 BSDF", "7 film and integrator loop"]
for label in order + sorted(set(totals) - set(order)):
    print(f"| {label} | {ns(totals[label]):.1f} |")
shading = sum(totals[l] for l in order[3:])
print(f"| shading (picking, stages 1-7) | {ns(shading):.1f} |")
print(f"| total process | {ns(sum(totals.values())):.1f} |  ({sum(totals.values())} samples, {runs} runs)")
