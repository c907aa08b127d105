//! `heighttonormal` without screen-space derivatives. MaterialX's GLSL builds the normal from
//! dFdx/dFdy of the height and of the node's `texcoord` input: n = (dT/dx, s·dH/dx) ×
//! (dT/dy, s·dH/dy), s = scale/16. Both tangents lie in the tangent plane of the height field
//! over the texcoord plane, so n does not depend on which two independent directions are
//! differentiated along: the builder differentiates along the geometry's UV0 axes instead of
//! the screen's, by central differences. The upstream graphs of `in` and `texcoord` are built
//! again with every read of UV0 (the `UV0` geomprop and the `texcoord` node) shifted by ±ε;
//! everything else (other geometry, interface inputs) is held fixed — a height that does not
//! vary with UV0 gives MaterialX's flat (0.5, 0.5, 1).

use super::{GraphBuilder, NodeResult, H};
use crate::ir::{GeomProp, ValueKind};
use mtlx::{DataType, SourcePos, Value as Literal};

/// The UV0 step of the central differences: 2⁻¹⁰, exact in binary. Texture lookups are
/// bilinear, so a step of about a texel of a 1k image behaves like the Sobel filter MaterialX
/// matches; f32 cancellation stays near 1e-4 of the height's scale.
const STEP: f32 = 1.0 / 1024.0;

/// The library function that turns the differences into the encoded normal
/// (stdlib/wgsl/convolution.wgsl).
const FROM_DIFFERENCES: &str = "mx_heighttonormal_from_differences";

impl GraphBuilder<'_> {
    /// The encoded normal of a `heighttonormal` node whose `in`, `scale` and `texcoord` are bound.
    pub(super) fn height_to_normal(&mut self, height: H, scale: H, texcoord: H, origin: &str, pos: &SourcePos) -> NodeResult {
        let shifted = |b: &mut Self, du: f32, dv: f32| (b.with_uv_shifted(height, [du, dv], pos), b.with_uv_shifted(texcoord, [du, dv], pos));
        let (h_u1, t_u1) = shifted(self, STEP, 0.0);
        let (h_u0, t_u0) = shifted(self, -STEP, 0.0);
        let (h_v1, t_v1) = shifted(self, 0.0, STEP);
        let (h_v0, t_v0) = shifted(self, 0.0, -STEP);
        let step = self.add(ValueKind::Constant(Literal::Floats(vec![STEP])), DataType::Float, origin.to_string(), pos.clone());
        let args = vec![h_u1, h_u0, h_v1, h_v0, t_u1, t_u0, t_v1, t_v0, scale, step];
        let kind = ValueKind::Call { function: FROM_DIFFERENCES.to_string(), args, geometry: false, closure: false };
        NodeResult::Single(self.add(kind, DataType::Vector3, origin.to_string(), pos.clone()))
    }

    /// `value` rebuilt with every read of UV0 upstream of it shifted by `delta` (the values
    /// that do not depend on UV0 are shared, not copied).
    fn with_uv_shifted(&mut self, value: H, delta: [f32; 2], pos: &SourcePos) -> H {
        // Upstream of `value`: the arena is in topological order, so one backward sweep marks it.
        let n = value.index() + 1;
        let mut upstream = vec![false; n];
        upstream[value.index()] = true;
        for i in (0..n).rev() {
            if !upstream[i] {
                continue;
            }
            match &self.graph.values[H::from_index(i)].kind {
                ValueKind::Call { args, .. } => args.iter().for_each(|a| upstream[a.index()] = true),
                ValueKind::Field { base, .. } => upstream[base.index()] = true,
                _ => {}
            }
        }
        let mut map: Vec<H> = (0..n).map(H::from_index).collect();
        for i in (0..n).filter(|&i| upstream[i]) {
            let v = self.graph.values[H::from_index(i)].clone();
            map[i] = match &v.kind {
                ValueKind::Geometry(GeomProp::Texcoord) => self.shift(H::from_index(i), &DataType::Vector2, delta, &v.origin, pos),
                ValueKind::Call { function, geometry: true, .. } if function == "mx_texcoord_vector2" => {
                    self.shift(H::from_index(i), &DataType::Vector2, delta, &v.origin, pos)
                }
                ValueKind::Call { function, geometry: true, .. } if function == "mx_texcoord_vector3" => {
                    self.shift(H::from_index(i), &DataType::Vector3, delta, &v.origin, pos)
                }
                ValueKind::Call { function, args, geometry, closure } => {
                    let new_args: Vec<H> = args.iter().map(|a| map[a.index()]).collect();
                    if new_args == *args {
                        H::from_index(i)
                    } else {
                        let kind = ValueKind::Call { function: function.clone(), args: new_args, geometry: *geometry, closure: *closure };
                        self.add(kind, v.ty.clone(), v.origin.clone(), v.pos.clone())
                    }
                }
                ValueKind::Field { base, field } if map[base.index()] != *base => {
                    let kind = ValueKind::Field { base: map[base.index()], field: field.clone() };
                    self.add(kind, v.ty.clone(), v.origin.clone(), v.pos.clone())
                }
                _ => H::from_index(i),
            };
        }
        map[value.index()]
    }

    /// `uv + delta` (a vector3 texcoord gets `delta` in x and y).
    fn shift(&mut self, uv: H, ty: &DataType, delta: [f32; 2], origin: &str, pos: &SourcePos) -> H {
        let (components, function) = match ty {
            DataType::Vector3 => (vec![delta[0], delta[1], 0.0], "mx_add_vector3"),
            _ => (delta.to_vec(), "mx_add_vector2"),
        };
        let d = self.add(ValueKind::Constant(Literal::Floats(components)), ty.clone(), origin.to_string(), pos.clone());
        let kind = ValueKind::Call { function: function.to_string(), args: vec![uv, d], geometry: false, closure: false };
        self.add(kind, ty.clone(), format!("{origin}+uv"), pos.clone())
    }
}
