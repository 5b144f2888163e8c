"""Sionna RT as the channel backend (issue #16; paper §IV-A: "a 3D model in Blender, imported into the
Sionna ray-tracing software"): the echo paths of a pose ray traced by Sionna RT (Hoydis et al., "Sionna
RT: differentiable ray tracing for radio propagation modeling", 2023) in a 3D scene, then beamformed by
our codebook and sent through our waveform synthesis and receiver unchanged.

The scene is our YAML scene extruded (:mod:`radioslam.scene.extrude`), each material its ITU-R P.2040
class (:class:`~radioslam.scene.materials.ItuMaterial`) with our scattering S as the scattering
coefficient and our directivity as the directive lobe's α_R (Degli-Esposti et al. 2007, the model both
use). The terminal, at ``radio.height_m``, carries one TX and one RX array per orientation, b/2 above and
below that height (the stacked arrays of :mod:`radioslam.sim.paths`), each a horizontal row of N
isotropic elements at λ/2, turned to the orientation's normal. TX and RX are co-located, so there is no
line of sight (``los=False``): the TX→RX leakage is ours, as with the built-in caster. Delays are
absolute (``normalize_delays=False``).

Per path p and orientation k Sionna gives the baseband coefficients A_p[m, n] from TX element n to RX
element m (``cir``). The beam's gain is then (eq. (4), ϖ·b):

    g_{i,p} = w̃_i^H A_p w̃_i^* · e(ψ_t)·e(ψ_r) · c(ε_t)·c(ε_r),

w̃_i our DFT weights in Sionna's element order (our element n at −n·d along the row: Sionna's element
N − 1 − n), e(ψ) = cos^{q/2} ψ the element pattern off the array normal (``element_exponent`` q, zero
behind), and c(ε) = |v_j^H a(sin ε/2)|/√N the factor of the 8×8 array's N rows steered by the beam's
elevation row j (:meth:`~radioslam.antenna.codebook.BeamSet.vertical_factor`; for the flat scan's j = 0
the rows fed alike, 1 in the horizontal plane, so a wall at the terminal's height sees today's beams). With
``synthetic_array`` (default) Sionna traces from each array's centre and applies the elements' phases
as plane waves (exact in the far field, beyond 2D²/λ ≈ 0.26 m here); without it every element pair is
traced (spherical wavefronts, 64× the paths).

A trace is the costly part (seconds a pose): its arrays (each orientation's coefficients, delays, angles,
interaction kinds, first bounces) can be kept in a :class:`TraceStore` under :meth:`SionnaChannel.trace_key`,
which hashes what they depend on (the scene's mesh and materials, the Mitsuba file, the arrays' geometry,
the carrier, the solver's options, the pose, Sionna's version). The codebook, element pattern and rows'
factor are applied after it, so a change of those reuses the trace.
"""

from __future__ import annotations

import hashlib
import json
import os
import sys
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import asdict, dataclass
from functools import cached_property
from pathlib import Path

import numpy as np

from radioslam.antenna.codebook import BeamSet
from radioslam.config import RadioConfig
from radioslam.scene.extrude import extruded_mesh, scene_mesh
from radioslam.scene.mesh import Mesh
from radioslam.scene.model import Scene
from radioslam.sim.channel_backend import TraceStore
from radioslam.sim.errors import SimulationError
from radioslam.sim.paths import EchoPaths, PathKind, leakage_path

INSTALL_HINT = ("pip install 'radioslam[sionna]', and an LLVM for Dr.Jit's CPU backend (Debian: apt install "
                "libllvm19; DRJIT_LIBLLVM_PATH=/usr/lib/x86_64-linux-gnu/libLLVM.so.19.1)")
DIFFUSE_FLAG = 2  # sionna.rt.constants.InteractionType.DIFFUSE
TRACE_FORMAT = 1  # raised whenever the stored arrays change meaning


@dataclass(frozen=True)
class SionnaOptions:
    """How Sionna RT traces: reflections up to ``max_depth``, diffuse scattering with ``samples`` rays per
    source (the monostatic terminal sees a wall off its normal only through them), the seed of its
    sampling."""

    max_depth: int = 2
    diffuse: bool = True
    samples: int = 200_000
    synthetic_array: bool = True
    seed: int = 1


def import_sionna():
    """sionna.rt and mitsuba (drjit loaded with them), or a one-line SimulationError saying how to install
    them."""
    if "DRJIT_LIBLLVM_PATH" not in os.environ:
        for candidate in ("/usr/lib/x86_64-linux-gnu/libLLVM.so.19.1", "/usr/lib/x86_64-linux-gnu/libLLVM-19.so"):
            if os.path.exists(candidate):
                os.environ["DRJIT_LIBLLVM_PATH"] = candidate
                break
    try:
        with _c_stderr_silenced():
            import drjit  # noqa: F401  (its LLVM backend fails here when no LLVM is found)
            import mitsuba as mi
            import sionna.rt as rt
    except Exception as exc:  # ImportError, or Dr.Jit's own when no LLVM is found
        reason = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        raise SimulationError(f"the sionna channel needs Sionna RT: {INSTALL_HINT} ({reason})",
                              field="--channel") from None
    return rt, mi


@contextmanager
def _c_stderr_silenced() -> Iterator[None]:
    """File descriptor 2 sent to /dev/null: Dr.Jit's search for an LLVM prints its failures from C there,
    which would break the one-line error (its exception says the same)."""
    sys.stderr.flush()
    saved = os.dup(2)
    try:
        with open(os.devnull, "w") as null:
            os.dup2(null.fileno(), 2)
            yield
    finally:
        os.dup2(saved, 2)
        os.close(saved)


def beam_gains(beams: BeamSet, coefficients: np.ndarray, orientation: int) -> np.ndarray:
    """g (B_k, P) on the beams of ``orientation`` (in beam order) of paths whose baseband coefficients
    (P, N_rx, N_tx) were traced with that orientation's arrays: w̃^H A w̃^*, complex64."""
    w = beams.weights()[:, ::-1]  # our element n at −n·d: Sionna's element N − 1 − n
    weights = w[beams.orientation == orientation].conj().astype(np.complex64)
    return np.einsum("bm,pmn,bn->bp", weights, coefficients.astype(np.complex64, copy=False), weights)


def element_factor(azimuth: np.ndarray, elevation: np.ndarray, exponent: float) -> np.ndarray:
    """cos^{q/2} ψ of the angle ψ off the array normal (amplitude, one way), 0 behind the array."""
    cos_psi = np.cos(elevation) * np.cos(azimuth)
    return np.where(cos_psi > 0, np.abs(cos_psi) ** (exponent / 2), 0.0)


def check_scene(scene: Scene) -> Mesh | None:
    """The scene's 3D mesh, every material of it with an ITU-R P.2040 class (else a one-line error);
    None for a Mitsuba scene (Sionna reads it as it is)."""
    if scene.spec.mitsuba is not None:
        return None
    mesh = extruded_mesh(scene)
    for m in np.unique(mesh.face_material):
        if scene.materials[m].itu is None:
            name = scene.material_names[m]
            raise SimulationError(f"material '{name}' names no ITU-R P.2040 class (itu:) for the sionna channel",
                                  field=f"materials.{name}.itu")
    return mesh


class SionnaChannel:
    """Echo paths of a scene's poses from Sionna RT (built once per scene)."""

    def __init__(self, scene: Scene, radio: RadioConfig, options: SionnaOptions | None = None,
                 cache: TraceStore | None = None):
        self.rt, self.mi = import_sionna()
        options = options or SionnaOptions(samples=radio.sionna_samples)
        self.radio, self.options, self.beams, self.cache = radio, options, BeamSet.from_config(radio), cache
        self.source, self.source_mesh = scene, check_scene(scene)
        self.scene = self._sionna_scene(scene, self.source_mesh)
        self.solver = self.rt.PathSolver()

    @cached_property
    def scene_digest(self) -> str:
        """:func:`scene_digest` of the scene, when a trace key is first asked for (a Mitsuba scene's files
        are read again for it)."""
        return scene_digest(self.source, self.source_mesh)

    def _sionna_scene(self, scene: Scene, mesh: Mesh | None):
        rt, radio = self.rt, self.radio
        out = self._loaded_scene(scene) if mesh is None else self._extruded_scene(scene, mesh)
        out.frequency = radio.carrier_hz
        array = dict(num_rows=1, num_cols=radio.array_elements, vertical_spacing=0.5, horizontal_spacing=0.5,
                     pattern="iso", polarization="V")
        out.tx_array, out.rx_array = rt.PlanarArray(**array), rt.PlanarArray(**array)
        for k in range(radio.orientations):
            out.add(rt.Transmitter(f"tx{k}", position=[0.0, 0.0, radio.height_m]))
            out.add(rt.Receiver(f"rx{k}", position=[0.0, 0.0, radio.height_m]))
        return out

    def _loaded_scene(self, scene: Scene):
        """Sionna's scene of a Mitsuba file, each radio material given its class's scattering (the file's
        bsdfs carry none: a monostatic terminal would see its walls only at normal incidence)."""
        out = self.rt.load_scene(scene.spec.mitsuba)
        used = {m.itu.value: m for m in scene.materials if m.itu is not None}  # the file's own win (last)
        for name, radio_material in out.radio_materials.items():  # Sionna names them itu_CLASS
            material = used.get(name.removeprefix("mat-").removeprefix("itu_"))
            if material is not None:
                radio_material.scattering_coefficient = material.scattering
                radio_material.scattering_pattern = self.rt.DirectivePattern(
                    alpha_r=max(1, int(round(material.directivity))))
        return out

    def _extruded_scene(self, scene: Scene, mesh: Mesh):
        """Sionna's scene of our extruded mesh, one object per material."""
        rt, mi = self.rt, self.mi
        out = rt.load_scene()
        objects = []
        for m in np.unique(mesh.face_material):
            material, name = scene.materials[m], scene.material_names[m]
            radio_material = rt.ITURadioMaterial(f"mat-{name}", material.itu.value, thickness=material.thickness_m,
                                                 scattering_coefficient=material.scattering)
            radio_material.scattering_pattern = rt.DirectivePattern(alpha_r=max(1, int(round(material.directivity))))
            part = mesh.of_material(int(m))
            shape = mi.Mesh(f"mesh-{name}", vertex_count=len(part.vertices), face_count=len(part.faces),
                            has_vertex_normals=False, has_vertex_texcoords=False)
            params = mi.traverse(shape)
            params["vertex_positions"] = mi.Float(part.vertices.astype(np.float32).ravel())
            params["faces"] = mi.UInt32(part.faces.astype(np.uint32).ravel())
            params.update()
            objects.append(rt.SceneObject(mi_mesh=shape, name=f"walls-{name}", radio_material=radio_material))
        out.edit(add=objects)
        return out

    def _place(self, pose: np.ndarray) -> None:
        radio, half = self.radio, self.radio.array_baseline_m / 2
        for k in range(radio.orientations):
            yaw = float(pose[2] + k * 2 * np.pi / radio.orientations)
            self.scene.get(f"tx{k}").position = self.mi.Point3f(float(pose[0]), float(pose[1]), radio.height_m + half)
            self.scene.get(f"rx{k}").position = self.mi.Point3f(float(pose[0]), float(pose[1]), radio.height_m - half)
            for name in (f"tx{k}", f"rx{k}"):
                self.scene.get(name).orientation = self.mi.Point3f(yaw, 0.0, 0.0)

    def trace(self, pose: np.ndarray):
        """Sionna's paths of the terminal at ``pose`` (x, y, θ)."""
        self._place(np.asarray(pose, dtype=np.float64))
        o = self.options
        return self.solver(self.scene, max_depth=o.max_depth, samples_per_src=o.samples, los=False,
                           synthetic_array=o.synthetic_array, specular_reflection=True,
                           diffuse_reflection=o.diffuse, refraction=True, seed=o.seed)

    def trace_key(self, pose: np.ndarray) -> str:
        """What a trace of ``pose`` depends on, hashed (SHA-256, hex)."""
        radio = self.radio
        doc = {"format": TRACE_FORMAT, "sionna": self.rt.__version__, "scene": self.scene_digest,
               "radio": [radio.carrier_hz, radio.array_elements, radio.height_m, radio.array_baseline_m,
                         radio.orientations], "options": asdict(self.options),
               "pose": [float(x) for x in np.asarray(pose, dtype=np.float64)]}
        return hashlib.sha256(json.dumps(doc, sort_keys=True).encode()).hexdigest()

    def traced(self, pose: np.ndarray) -> dict[str, np.ndarray]:
        """The arrays of a trace of ``pose``, each with the orientation first: ``coefficients``
        (K, rx_ant, tx_ant, P), ``tau``, ``theta_t``, ``phi_t``, ``theta_r``, ``phi_r`` and ``diffuse``
        (K, P), ``first`` (K, P, 2) the first bounce. From the cache when it holds them, else traced
        (and stored)."""
        key = None if self.cache is None else self.trace_key(pose)
        arrays = None if key is None else self.cache.load(key)
        if arrays is None:
            arrays = self._trace_arrays(pose)
            if key is not None:
                self.cache.store(key, arrays)
        return arrays

    def _trace_arrays(self, pose: np.ndarray) -> dict[str, np.ndarray]:
        traced = self.trace(pose)
        k = np.arange(self.radio.orientations)  # orientation k's TX k to its RX k only
        # baseband coefficients (rx, rx_ant, tx, tx_ant, paths), absolute delays
        a = np.asarray(traced.cir(normalize_delays=False, out_type="numpy")[0])[..., 0]
        arrays = {"coefficients": a[k, :, k].astype(np.complex64), "tau": np.asarray(traced.tau.numpy())[k, k]}
        for name in ("theta_t", "phi_t", "theta_r", "phi_r"):
            arrays[name] = np.asarray(getattr(traced, name).numpy())[k, k]
        kinds = np.asarray(traced.interactions.numpy())  # (depth, rx, tx, paths) (synthetic)
        arrays["diffuse"] = np.any((kinds[:, k, k] & DIFFUSE_FLAG) != 0, axis=0)
        arrays["first"] = np.asarray(traced.vertices.numpy())[0, k, k][..., :2]  # (depth, rx, tx, paths, 3)
        return arrays

    def paths(self, pose: np.ndarray, leakage: bool = True) -> EchoPaths:
        """Every echo path of the terminal at ``pose``, shortest delay first, with its gain on every beam
        (``beam_gain``, complex64 as Sionna's coefficients: beams × paths is the largest array of a pose)."""
        pose = np.asarray(pose, dtype=np.float64)
        arrays = self.traced(pose)
        parts = [self._orientation_paths(pose, k, {name: x[k] for name, x in arrays.items()})
                 for k in range(self.radio.orientations)]
        if leakage and np.isfinite(self.radio.isolation_db):  # its gain is the arrays' coupling (beam_path_gains)
            parts.append((*leakage_path(self.radio), np.array([PathKind.LEAKAGE]), None))
        delay, amplitude, angle, segment, point, kind = (np.concatenate(x) for x in zip(*(p[:6] for p in parts)))
        order = np.argsort(delay, kind="stable")
        slot = np.empty(len(delay), dtype=np.int64)  # where each path goes in delay order
        slot[order] = np.arange(len(delay))
        gains = np.zeros((len(self.beams), len(delay)), dtype=np.complex64)
        start = 0
        for part in parts:
            count = len(part[0])
            if part[6] is not None:  # this orientation's beams only; 0 on the others
                rows, block = part[6]
                gains[np.ix_(rows, slot[start:start + count])] = block
            start += count
        return EchoPaths(delay[order], amplitude[order].astype(np.complex128), angle[order],
                         kind[order].astype(np.int8), segment[order], point[order], beam_gain=gains)

    def _orientation_paths(self, pose, k, trace):
        """(delay, amplitude, angle, segment, point, kind, (rows, gains)) of the paths traced for orientation
        k (``trace``: :meth:`traced`'s arrays of that orientation), the gains on that orientation's beams."""
        delay, coefficients = trace["tau"], trace["coefficients"]  # (P,), (rx_ant, tx_ant, P)
        valid = (delay > 0) & np.any(coefficients != 0, axis=(0, 1))
        coefficients = np.moveaxis(coefficients[..., valid], -1, 0)  # (P, rx_ant, tx_ant)
        yaw = pose[2] + k * 2 * np.pi / self.radio.orientations
        q = self.radio.element_exponent
        rows = np.flatnonzero(self.beams.orientation == k)
        factor = np.ones((len(rows), int(valid.sum())), dtype=np.float32)
        for theta, phi in ((trace["theta_t"][valid], trace["phi_t"][valid]),
                           (trace["theta_r"][valid], trace["phi_r"][valid])):
            elevation = np.pi / 2 - theta  # the rows' factor of each beam's elevation row j, then the element's
            factor *= self.beams.vertical_factor(elevation)[rows] * element_factor(phi - yaw, elevation, q)
        gains = beam_gains(self.beams, coefficients, k) * factor
        kind = np.where(trace["diffuse"][valid], PathKind.DIFFUSE, PathKind.SPECULAR)
        angle = np.angle(np.exp(1j * (trace["phi_t"][valid] - pose[2])))
        return (delay[valid].astype(np.float64), np.ones(len(kind), dtype=np.complex128), angle,
                np.full(len(kind), -1), trace["first"][valid].astype(np.float64), kind, (rows, gains))


def scene_digest(scene: Scene, mesh: Mesh | None) -> str:
    """SHA-256 of what Sionna's scene is built from: the mesh (the extruded one, or the Mitsuba file's with
    the file itself), every material's parameters."""
    digest = hashlib.sha256()
    if mesh is None:
        digest.update(Path(scene.spec.mitsuba).read_bytes())
        mesh = scene_mesh(scene)
    for array in (mesh.vertices, mesh.faces, mesh.face_material):
        digest.update(np.ascontiguousarray(array).tobytes())
    digest.update(repr((scene.material_names, scene.materials, mesh.material_names)).encode())
    return digest.hexdigest()
