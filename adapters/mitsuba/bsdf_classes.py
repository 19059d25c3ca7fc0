"""Mitsuba 0.5's Ward, modified Phong and Ashikhmin-Shirley BSDFs: the classes themselves.

Built against the Mitsuba variant that is set when this module is loaded: `bsdfs.register_bsdfs`
loads it once per variant (a class derives from that variant's ``mi.BSDF``) and registers its
three classes. Their formulas and the sampling they follow are described in `bsdfs`."""

from __future__ import annotations

import math
from enum import StrEnum

import drjit as dr
import mitsuba as mi
import numpy as np

from brdfremap.adapters.mitsuba.bsdfs import (
    ALPHA_MIN,
    INV_PI,
    INV_TWOPI,
    TABLE_SIZE,
    WARD_VARIANTS,
    _as_exponent,
    _bool,
    _color,
    _get,
    _has,
    conductor_preset,
    rough_transmittance_table,
    trim_scale,
)
from brdfremap.core.data.appearance import eta_k_from_reflectivity

if mi.variant() is None:
    raise RuntimeError("set a Mitsuba variant (mitsuba.set_variant) before loading the BSDF classes")

Flags = mi.BSDFFlags



class Form(StrEnum):
    """What Mitsuba 0.5's microfacet model is over: a conductor's Fresnel, or a plastic's (a
    dielectric over a Lambertian)."""

    CONDUCTOR = "conductor"
    PLASTIC = "plastic"

def opaque_float(x: float):
    v = mi.Float(float(x))
    dr.make_opaque(v)
    return v


def opaque_color(c):
    v = mi.Color3f(*[float(x) for x in c])
    dr.make_opaque(v)
    return v


def host(v) -> tuple[float, ...]:
    a = np.array(v, dtype=float).ravel()
    return tuple(float(x) for x in (a if a.size >= 3 else np.repeat(a[:1], 3)))[:3]


def host1(v) -> float:
    return float(np.array(v, dtype=float).ravel()[0])


def cos_hemisphere(u):
    return mi.warp.square_to_cosine_hemisphere(u)


def cos_hemisphere_pdf(wo):
    return mi.warp.square_to_cosine_hemisphere_pdf(wo)


def lobe_flags(has_spec: bool, has_diff: bool):
    comps = []
    if has_spec:
        comps.append(Flags.GlossyReflection | Flags.FrontSide)
    if has_diff:
        comps.append(Flags.DiffuseReflection | Flags.FrontSide)
    return comps


class _Base(mi.BSDF):
    """Shared parameter handling: reflectances with Mitsuba 0.5's safeguard, traverse, flags."""

    has_diffuse_param = True

    def __init__(self, props):
        mi.BSDF.__init__(self, props)
        self.ks_in = _color(props, "specular_reflectance", self.default_ks)
        self.kd_in = _color(props, "diffuse_reflectance", 0.5) if self.has_diffuse_param else (0.0,) * 3
        self.conserve = _bool(props, "ensure_energy_conservation", True)
        self.ks = opaque_color(self.ks_in)
        self.kd = opaque_color(self.kd_in)

    def _trim(self) -> None:
        """Recompute the effective reflectances and sampling weight from the user's values."""
        ks, kd = host(self.ks), host(self.kd)
        self.ks_in, self.kd_in = ks, kd
        s = trim_scale(ks, kd) if (self.conserve and self.has_diffuse_param) else 1.0
        self.scale = s
        self.ks_eff = opaque_color([x * s for x in ks])
        self.kd_eff = opaque_color([x * s for x in kd])
        avg_s, avg_d = float(np.mean(ks)) * s, float(np.mean(kd)) * s
        self._set_spec_weight(avg_s, avg_d)
        comps = lobe_flags(True, self.has_diffuse_param)
        self.m_components = comps
        flags = comps[0]
        for c in comps[1:]:
            flags = flags | c
        self.m_flags = flags

    def _set_spec_weight(self, avg_s: float, avg_d: float) -> None:
        # Opaque: a value that changes between renders must not be baked into the kernel.
        self.spec_weight_h = avg_s / (avg_s + avg_d) if avg_s + avg_d > 0 else 1.0
        self.spec_weight = opaque_float(self.spec_weight_h)

    def traverse(self, callback):
        callback.put("specular_reflectance", self.ks, mi.ParamFlags.Differentiable)
        if self.has_diffuse_param:
            callback.put("diffuse_reflectance", self.kd, mi.ParamFlags.Differentiable)

    def parameters_changed(self, keys):
        self._params_changed()

    def _params_changed(self) -> None:
        self._trim()

    def eval_pdf(self, ctx, si, wo, active=True):
        return self.eval(ctx, si, wo, active), self.pdf(ctx, si, wo, active)

    @staticmethod
    def _above(wi, wo, active):
        """Both directions above the surface (these BSDFs reflect only)."""
        return mi.Bool(active) & (mi.Frame3f.cos_theta(wi) > 0) & (mi.Frame3f.cos_theta(wo) > 0)

    def sample(self, ctx, si, sample1, sample2, active=True):
        return self._mix_sample(ctx, si, sample1, sample2, active, self._sample_spec, self.spec_weight)

    def _mix_sample(self, ctx, si, sample1, sample2, active, spec_dir, spec_prob):
        """Choose a lobe with probability spec_prob (per lane), sample it, weight = eval / pdf."""
        wi = si.wi
        active = mi.Bool(active) & (mi.Frame3f.cos_theta(wi) > 0)
        choose_spec = sample1 < spec_prob
        wo_s = spec_dir(wi, sample2)
        wo_d = cos_hemisphere(sample2)
        wo = dr.select(choose_spec, wo_s, wo_d)
        bs = dr.zeros(mi.BSDFSample3f)
        bs.wo = wo
        bs.eta = 1.0
        bs.sampled_component = dr.select(choose_spec, mi.UInt32(0), mi.UInt32(1))
        bs.sampled_type = dr.select(choose_spec, mi.UInt32(+Flags.GlossyReflection),
                                    mi.UInt32(+Flags.DiffuseReflection))
        value, pdf = self.eval_pdf(ctx, si, wo, active)
        bs.pdf = pdf
        ok = active & (pdf > 0) & (mi.Frame3f.cos_theta(wo) > 0)
        return bs, dr.select(ok, value / dr.maximum(pdf, 1e-20), 0.0)


class _Rough(_Base):
    """A roughness given as ``alpha`` (isotropic, exposed as ``alpha``) or ``alpha_u``/``alpha_v``."""

    def _read_alpha(self, props) -> None:
        a = _get(props, "alpha", 0.1)
        self.isotropic = not (_has(props, "alpha_u") or _has(props, "alpha_v"))
        self.alpha_u = opaque_float(_get(props, "alpha_u", a))
        self.alpha_v = opaque_float(_get(props, "alpha_v", a))

    def _alphas(self) -> tuple[float, float]:
        """The roughnesses as floats, clamped where Mitsuba 0.5 clamps them."""
        return max(host1(self.alpha_u), ALPHA_MIN), max(host1(self.alpha_v), ALPHA_MIN)

    def traverse(self, callback):
        super().traverse(callback)
        if self.isotropic:
            callback.put("alpha", self.alpha_u, mi.ParamFlags.Differentiable)
        else:
            callback.put("alpha_u", self.alpha_u, mi.ParamFlags.Differentiable)
            callback.put("alpha_v", self.alpha_v, mi.ParamFlags.Differentiable)

    def parameters_changed(self, keys):
        if self.isotropic:
            self.alpha_v = mi.Float(self.alpha_u)
        self._params_changed()


class Ward(_Rough):
    """Mitsuba 0.5's anisotropic Ward BSDF (ward.cpp): variants ward, ward-duer, balanced."""

    default_ks = 0.2

    def __init__(self, props):
        super().__init__(props)
        variant = _get(props, "variant", "balanced")
        if variant not in WARD_VARIANTS:
            raise ValueError(f"ward: variant must be one of {', '.join(WARD_VARIANTS)}, got {variant!r}")
        self.variant = variant
        self._read_alpha(props)
        self._params_changed()

    def _params_changed(self):
        self._trim()
        au, av = self._alphas()
        self.au, self.av = opaque_float(au), opaque_float(av)
        self.aniso_ratio = opaque_float(av / au)

    def _spec(self, wi, wo):
        h = wi + wo
        ci, co = mi.Frame3f.cos_theta(wi), mi.Frame3f.cos_theta(wo)
        if self.variant == "ward":
            f1 = 1.0 / (4.0 * dr.pi * self.au * self.av * dr.sqrt(ci * co))
        elif self.variant == "ward-duer":
            f1 = 1.0 / (4.0 * dr.pi * self.au * self.av * ci * co)
        else:
            f1 = dr.dot(h, h) / (dr.pi * self.au * self.av * dr.square(dr.square(h.z)))
        f2, f3 = h.x / self.au, h.y / self.av
        spec = f1 * dr.exp(-(f2 * f2 + f3 * f3) / (h.z * h.z))
        return dr.select(spec > 1e-10, spec, 0.0)

    def eval(self, ctx, si, wo, active=True):
        wi = si.wi
        co = mi.Frame3f.cos_theta(wo)
        active = self._above(wi, wo, active)
        value = self.ks_eff * self._spec(wi, wo) + self.kd_eff * INV_PI
        return dr.select(active, value * co, 0.0)

    def _spec_pdf(self, wi, wo):
        h = dr.normalize(wi + wo)
        f1 = 1.0 / (4.0 * dr.pi * self.au * self.av * dr.dot(h, wi) * h.z * h.z * h.z)
        f2, f3 = h.x / self.au, h.y / self.av
        p = f1 * dr.exp(-(f2 * f2 + f3 * f3) / (h.z * h.z))
        return dr.select((dr.dot(h, wi) > 0) & (h.z > 0), p, 0.0)

    def pdf(self, ctx, si, wo, active=True):
        wi = si.wi
        active = self._above(wi, wo, active)
        w = self.spec_weight
        p = w * self._spec_pdf(wi, wo) + (1.0 - w) * cos_hemisphere_pdf(wo)
        return dr.select(active, p, 0.0)

    def _sample_spec(self, wi, u):
        # Ward's half-vector sampling (Walter's notes), as in Mitsuba 0.5.
        phi = dr.atan(self.aniso_ratio * dr.tan(2.0 * dr.pi * u.y))
        phi = dr.select(u.y > 0.5, phi + dr.pi, phi)
        c, s = dr.cos(phi), dr.sin(phi)
        denom = c * c / (self.au * self.au) + s * s / (self.av * self.av)
        theta = dr.atan(dr.safe_sqrt(-dr.log(dr.maximum(u.x, 1e-12)) / denom))
        st = dr.sin(theta)
        h = mi.Vector3f(st * c, st * s, dr.cos(theta))
        return 2.0 * dr.dot(wi, h) * h - wi

    def to_string(self):
        return (f"Ward[variant={self.variant}, alpha=({host1(self.alpha_u):g}, {host1(self.alpha_v):g}), "
                f"specular_reflectance={self.ks_in}, diffuse_reflectance={self.kd_in}, trim={self.scale:g}]")


class Phong(_Base):
    """Mitsuba 0.5's modified Phong BSDF (phong.cpp)."""

    default_ks = 0.2

    def __init__(self, props):
        super().__init__(props)
        n = _get(props, "exponent", 30.0)
        self.exponent = opaque_float(n)
        self._params_changed()

    def _params_changed(self):
        self._trim()
        self.n_host = max(host1(self.exponent), 0.0)
        self.n = opaque_float(self.n_host)

    def traverse(self, callback):
        super().traverse(callback)
        callback.put("exponent", self.exponent, mi.ParamFlags.Differentiable)

    def _cos_alpha(self, wi, wo):
        r = mi.Vector3f(-wi.x, -wi.y, wi.z)
        return dr.dot(wo, r)

    def eval(self, ctx, si, wo, active=True):
        wi = si.wi
        co = mi.Frame3f.cos_theta(wo)
        active = self._above(wi, wo, active)
        a = self._cos_alpha(wi, wo)
        spec = dr.select(a > 0, (self.n + 2.0) * INV_TWOPI * dr.power(dr.maximum(a, 1e-30), self.n), 0.0)
        value = self.ks_eff * spec + self.kd_eff * INV_PI
        return dr.select(active, value * co, 0.0)

    def pdf(self, ctx, si, wo, active=True):
        wi = si.wi
        active = self._above(wi, wo, active)
        a = self._cos_alpha(wi, wo)
        ps = dr.select(a > 0, (self.n + 1.0) * INV_TWOPI * dr.power(dr.maximum(a, 1e-30), self.n), 0.0)
        w = self.spec_weight
        return dr.select(active, w * ps + (1.0 - w) * cos_hemisphere_pdf(wo), 0.0)

    def _sample_spec(self, wi, u):
        r = mi.Vector3f(-wi.x, -wi.y, wi.z)
        cos_a = dr.power(u.y, 1.0 / (self.n + 1.0))
        sin_a = dr.safe_sqrt(1.0 - cos_a * cos_a)
        phi = 2.0 * dr.pi * u.x
        local = mi.Vector3f(sin_a * dr.cos(phi), sin_a * dr.sin(phi), cos_a)
        return mi.Frame3f(r).to_world(local)

    def to_string(self):
        return (f"Phong[exponent={self.n_host:g}, specular_reflectance={self.ks_in}, "
                f"diffuse_reflectance={self.kd_in}, trim={self.scale:g}]")


class AshikhminShirley(_Rough):
    """Microfacet BSDF with Mitsuba 0.5's `as` distribution (anisotropic Phong, n = 2/alpha^2 - 2).

    ``form="conductor"``: Mitsuba 0.5's roughconductor (Fresnel from ``material``, ``eta``/``k``,
    or ``reflectivity``/``edge_tint``), times ``specular_reflectance``.
    ``form="plastic"``: Mitsuba 0.5's roughplastic (dielectric ``int_ior`` over a Lambertian
    ``diffuse_reflectance``, linear diffuse)."""

    default_ks = 1.0

    def __init__(self, props):
        given = _get(props, "form", Form.CONDUCTOR)
        if given not in tuple(Form):
            raise ValueError(f"ashikhmin_shirley: form must be conductor or plastic, got {given!r}")
        self.form = form = Form(given)
        self.has_diffuse_param = form == Form.PLASTIC
        super().__init__(props)
        self._read_alpha(props)
        if form == Form.CONDUCTOR:
            if _has(props, "material"):
                eta, k = conductor_preset(props.get("material"))
            elif _has(props, "reflectivity"):
                r = _color(props, "reflectivity", 0.9)
                g = _color(props, "edge_tint", 0.5)
                e, kk = eta_k_from_reflectivity(r, g)
                eta, k = tuple(e), tuple(kk)
            else:
                eta, k = _color(props, "eta", 0.0), _color(props, "k", 1.0)
            self.eta, self.k = opaque_color(eta), opaque_color(k)
        else:
            ior = _get(props, "int_ior", 1.49)
            ext = _get(props, "ext_ior", 1.000277)
            self.ext_ior = float(ext)
            self.int_ior = opaque_float(ior)
        self._params_changed()

    def _params_changed(self):
        # Mitsuba 0.5's roughplastic checks each reflectance against 1 on its own; its
        # roughconductor does not check at all.
        ks, kd = host(self.ks), host(self.kd)
        self._trim()
        if self.form == Form.PLASTIC:
            s = trim_scale(ks, (0.0, 0.0, 0.0)) if self.conserve else 1.0
            sd = trim_scale(kd, (0.0, 0.0, 0.0)) if self.conserve else 1.0
            self.scale = min(s, sd)
            self.ks_eff = opaque_color([x * s for x in ks])
            self.kd_eff = opaque_color([x * sd for x in kd])
            self._set_spec_weight(float(np.mean(ks)) * s, float(np.mean(kd)) * sd)
        else:
            self.scale = 1.0
            self.ks_eff = opaque_color(ks)
            # Values set through traverse arrive as literals: opaque, or each change recompiles.
            self.eta_eff, self.k_eff = opaque_color(host(self.eta)), opaque_color(host(self.k))
        au, av = self._alphas()
        self.au_h, self.av_h = au, av
        self.au, self.av = opaque_float(au), opaque_float(av)
        eu, ev = _as_exponent(au), _as_exponent(av)
        self.eu, self.ev = opaque_float(eu), opaque_float(ev)
        self.norm = opaque_float(math.sqrt((eu + 2) * (ev + 2)) * INV_TWOPI)
        self.anisotropic = eu != ev
        self.phi_ratio = opaque_float(math.sqrt((eu + 2) / (ev + 2)))
        if self.form == Form.PLASTIC:
            self.eta_h = host1(self.int_ior) / self.ext_ior
            self.eta_d = opaque_float(self.eta_h)
            table, fdr = rough_transmittance_table(round(0.5 * (au + av), 6), round(self.eta_h, 6))
            self.t_table = mi.Float(table)
            self.diff_scale = opaque_float(INV_PI / (1.0 - fdr) / (self.eta_h * self.eta_h))
            self.fdr = fdr
        else:
            self._set_spec_weight(1.0, 0.0)

    def traverse(self, callback):
        super().traverse(callback)
        if self.form == Form.CONDUCTOR:
            callback.put("eta", self.eta, mi.ParamFlags.Differentiable)
            callback.put("k", self.k, mi.ParamFlags.Differentiable)
        else:
            callback.put("int_ior", self.int_ior, mi.ParamFlags.Differentiable)

    # --- the distribution (Mitsuba 0.5 microfacet.h, EPhong with the AS anisotropic extension)
    def _D(self, m):
        ct = mi.Frame3f.cos_theta(m)
        s2 = dr.maximum(1.0 - ct * ct, 0.0)
        e = dr.select(s2 > 1e-12, (self.eu * m.x * m.x + self.ev * m.y * m.y) / s2, self.eu)
        return dr.select(ct > 0, self.norm * dr.power(dr.maximum(ct, 1e-30), e), 0.0)

    def _G1(self, v, m):
        vz = mi.Frame3f.cos_theta(v)
        s2 = dr.maximum(1.0 - vz * vz, 0.0)
        tan = dr.sqrt(s2) / dr.maximum(dr.abs(vz), 1e-12)
        inv_s2 = dr.select(s2 > 1e-12, 1.0 / s2, 0.0)
        alpha = dr.sqrt((v.x * v.x * self.au * self.au + v.y * v.y * self.av * self.av) * inv_s2)
        alpha = dr.select(s2 > 1e-12, alpha, self.au)
        a = 1.0 / dr.maximum(alpha * tan, 1e-12)
        g = dr.select(a >= 1.6, 1.0, (3.535 * a + 2.181 * a * a) / (1.0 + 2.276 * a + 2.577 * a * a))
        return dr.select(dr.dot(v, m) * vz > 0, g, 0.0)

    def _sample_m(self, u):
        if not self.anisotropic:
            phi = 2.0 * dr.pi * u.y
        else:
            phi = dr.atan(self.phi_ratio * dr.tan(2.0 * dr.pi * u.y))
            phi = dr.select(u.y > 0.5, phi + dr.pi, phi)
        c, s = dr.cos(phi), dr.sin(phi)
        e = self.eu * c * c + self.ev * s * s
        ct = dr.power(u.x, 1.0 / (e + 2.0))
        st = dr.safe_sqrt(1.0 - ct * ct)
        return mi.Vector3f(st * c, st * s, ct)

    def _fresnel_conductor(self, c):
        c2 = c * c
        s2 = 1.0 - c2
        eta, k = self.eta_eff, self.k_eff
        t1 = eta * eta - k * k - s2
        a2pb2 = dr.safe_sqrt(t1 * t1 + 4.0 * k * k * eta * eta)
        a = dr.safe_sqrt(0.5 * (a2pb2 + t1))
        term1 = a2pb2 + c2
        term2 = 2.0 * a * c
        rs = (term1 - term2) / (term1 + term2)
        term3 = a2pb2 * c2 + s2 * s2
        term4 = term2 * s2
        # At normal incidence p is s; for eta = k = 0 (a preset's channel) term3 + term4 is 0 there.
        rp = dr.select(term3 + term4 > 1e-20, rs * (term3 - term4) / (term3 + term4), rs)
        return 0.5 * (rp + rs)

    def _fresnel_dielectric(self, c):
        f, _, _, _ = mi.fresnel(c, self.eta_d)
        return f

    def _transmittance(self, mu):
        x = dr.clip(mu, 0.0, 1.0) * (TABLE_SIZE - 1)
        i0 = dr.minimum(mi.UInt32(dr.floor(x)), TABLE_SIZE - 2)
        t = x - mi.Float(i0)
        a = dr.gather(mi.Float, self.t_table, i0)
        b = dr.gather(mi.Float, self.t_table, i0 + 1)
        return a + (b - a) * t

    def _spec_value(self, wi, wo):
        h = dr.normalize(wi + wo)
        ci = mi.Frame3f.cos_theta(wi)
        model = self._D(h) * self._G1(wi, h) * self._G1(wo, h) / (4.0 * ci)
        d = dr.dot(wi, h)
        if self.form == Form.CONDUCTOR:
            return self.ks_eff * self._fresnel_conductor(d) * model
        return self.ks_eff * (self._fresnel_dielectric(d) * model)

    def eval(self, ctx, si, wo, active=True):
        wi = si.wi
        ci, co = mi.Frame3f.cos_theta(wi), mi.Frame3f.cos_theta(wo)
        active = self._above(wi, wo, active)
        value = self._spec_value(wi, wo)
        if self.form == Form.PLASTIC:
            t12, t21 = self._transmittance(ci), self._transmittance(co)
            value = value + self.kd_eff * (self.diff_scale * co * t12 * t21)
        return dr.select(active, value, 0.0)

    def _spec_prob(self, wi):
        if self.form == Form.CONDUCTOR:
            return mi.Float(1.0)
        # Mitsuba 0.5 roughplastic: share samples by the interface's reflectance at wi.
        w = self.spec_weight
        ps = 1.0 - self._transmittance(mi.Frame3f.cos_theta(wi))
        return ps * w / dr.maximum(ps * w + (1.0 - ps) * (1.0 - w), 1e-12)

    def _spec_pdf(self, wi, wo):
        h = dr.normalize(wi + wo)
        d = dr.dot(wo, h)
        p = self._D(h) * mi.Frame3f.cos_theta(h) / dr.maximum(4.0 * dr.abs(d), 1e-12)
        return dr.select(d > 0, p, 0.0)

    def pdf(self, ctx, si, wo, active=True):
        wi = si.wi
        active = self._above(wi, wo, active)
        ps = self._spec_prob(wi)
        p = ps * self._spec_pdf(wi, wo)
        if self.form == Form.PLASTIC:
            p = p + (1.0 - ps) * cos_hemisphere_pdf(wo)
        return dr.select(active, p, 0.0)

    def _sample_spec(self, wi, u):
        m = self._sample_m(u)
        return 2.0 * dr.dot(wi, m) * m - wi

    def sample(self, ctx, si, sample1, sample2, active=True):
        return self._mix_sample(ctx, si, sample1, sample2, active, self._sample_spec, self._spec_prob(si.wi))

    def to_string(self):
        return f"AshikhminShirley[form={self.form}, alpha=({self.au_h:g}, {self.av_h:g})]"
