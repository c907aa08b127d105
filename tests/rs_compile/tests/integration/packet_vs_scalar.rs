//! The packet writer against the scalar writer (its oracle): every function of
//! tests/wgsl/packet_straight.wgsl, packet_branches.wgsl (varying `if`s, returns inside them,
//! loops that lanes leave at different iterations, calls guarded by the selects they feed), packet_structs.wgsl and packet_tables.wgsl
//! (gathers), as packet Rust (tests/out/packet/) on every SIMD level this
//! machine has (plus `Emu<16>` and `Emu<1>`), and as scalar Rust (tests/out/rs_wgsl/), on the
//! same seeded inputs — lanes differ from each other, so a lane mix-up fails. Values must agree
//! to 1e-5 relative (`max(1, |x|)`): the writers may order a dot product's sums differently
//! (glam's SIMD `Vec4`) and fuse `mul_add` where the scalar writer rounds twice, a few ulp;
//! integers and exact operations agree bit for bit within that bound.

use glam::{Vec2, Vec3, Vec4};
use uplift_rs_snapshots::packet_packet_branches as pb;
use uplift_rs_snapshots::packet_packet_straight as p;
use uplift_rs_snapshots::packet_packet_structs as pst;
use uplift_rs_snapshots::packet_packet_tables as pt;
use uplift_rs_snapshots::wgsl_packet_tables as stb;
use uplift_rs_snapshots::wgsl_packet_structs as sst;
use uplift_rs_snapshots::wgsl_packet_branches as sb;
use uplift_rs_snapshots::wgsl_packet_straight as sc;
use uplift_simd::{F32s, I32s, Level, Simd, WithSimd};

const N: usize = 256;

fn inputs(seed: u64, lo: f32, hi: f32) -> Vec<f32> {
    let mut rng = uplift_base::rng::SplitMix64::new(seed);
    (0..N).map(|_| rng.range(lo, hi)).collect()
}

fn close(x: f32, y: f32) -> bool {
    (x.is_nan() && y.is_nan()) || (x - y).abs() <= 1e-5 * x.abs().max(1.0)
}

/// The packet `f` over every input chunk, its lanes written out.
fn lanes<S: Simd>(_: S, mut f: impl FnMut(usize) -> Vec<Vec<f32>>) -> Vec<Vec<f32>> {
    let mut out: Vec<Vec<f32>> = Vec::new();
    for start in (0..N).step_by(S::LANES) {
        let r = f(start);
        if out.is_empty() {
            out = vec![Vec::new(); r.len()];
        }
        for (c, col) in r.into_iter().enumerate() {
            out[c].extend(col);
        }
    }
    out
}

fn cols<S: Simd, const K: usize>(v: [S::F; K]) -> Vec<Vec<f32>> {
    v.iter()
        .map(|x| {
            let mut o = vec![0.0; S::LANES];
            x.write_to(&mut o);
            o
        })
        .collect()
}

struct Compare;

impl WithSimd for Compare {
    type Output = Vec<String>;
    #[inline(always)]
    fn with_simd<S: Simd>(self, s: S) -> Vec<String> {
        let (a, b, c) = (inputs(1, -3.0, 3.0), inputs(2, -3.0, 3.0), inputs(3, -3.0, 3.0));
        let (d, e, f) = (inputs(4, -2.0, 2.0), inputs(5, -2.0, 2.0), inputs(6, 0.0, 1.0));
        let ints: Vec<i32> = inputs(7, -5000.0, 5000.0).iter().map(|x| *x as i32).collect();
        let uints: Vec<u32> = inputs(8, 0.0, 4.0e9).iter().map(|x| *x as u32).collect();
        let mut failures = Vec::new();
        let mut check = |name: &str, got: Vec<Vec<f32>>, want: &dyn Fn(usize) -> Vec<f32>| {
            for i in 0..N {
                let w = want(i);
                for (c, wc) in w.iter().enumerate() {
                    if !close(got[c][i], *wc) && failures.len() < 20 {
                        failures.push(format!("{}: {name} point {i} component {c}: packet {}, scalar {wc}", S::NAME, got[c][i]));
                    }
                }
            }
        };
        let v3 = |x: &[f32], y: &[f32], z: &[f32], i: usize| -> [S::F; 3] { [s.load(&x[i..]), s.load(&y[i..]), s.load(&z[i..])] };

        check("poly", lanes(s, |i| cols::<S, 1>([p::poly(s, s.load(&a[i..]))])), &|i| vec![sc::poly(a[i])]);
        check("shade", lanes(s, |i| cols::<S, 3>(p::shade(s, v3(&a, &b, &c, i), v3(&d, &e, &f, i), v3(&f, &e, &d, i)))), &|i| {
            sc::shade(Vec3::new(a[i], b[i], c[i]), Vec3::new(d[i], e[i], f[i]), Vec3::new(f[i], e[i], d[i])).to_array().to_vec()
        });
        check(
            "mixes",
            lanes(s, |i| cols::<S, 4>(p::mixes(s, [s.load(&a[i..]), s.load(&b[i..]), s.load(&c[i..]), s.load(&d[i..])], [s.load(&e[i..]), s.load(&f[i..]), s.load(&a[i..]), s.load(&c[i..])], s.load(&f[i..])))),
            &|i| sc::mixes(Vec4::new(a[i], b[i], c[i], d[i]), Vec4::new(e[i], f[i], a[i], c[i]), f[i]).to_array().to_vec(),
        );
        check("hashes", lanes(s, |i| cols::<S, 1>([p::hashes(s, s.load_u(&uints[i..]), s.load_i(&ints[i..]))])), &|i| vec![sc::hashes(uints[i], ints[i])]);
        check("pick", lanes(s, |i| cols::<S, 1>([p::pick(s, s.load(&a[i..]), s.load(&b[i..]))])), &|i| vec![sc::pick(a[i], b[i])]);
        check("locals", lanes(s, |i| cols::<S, 2>(p::locals(s, [s.load(&a[i..]), s.load(&d[i..])]))), &|i| sc::locals(Vec2::new(a[i], d[i])).to_array().to_vec());
        check("calls", lanes(s, |i| cols::<S, 1>([p::calls(s, s.load(&a[i..]), v3(&b, &c, &d, i))])), &|i| vec![sc::calls(a[i], Vec3::new(b[i], c[i], d[i]))]);
        check(
            "converts",
            lanes(s, |i| cols::<S, 1>([p::converts(s, s.load(&a[i..])).to_f32()])),
            &|i| vec![sc::converts(a[i]) as f32],
        );
        // Varying ifs: inputs in [-3, 3] and [0, 1] send lanes both ways.
        check("branches", lanes(s, |i| cols::<S, 1>([pb::branches(s, s.load(&a[i..]), s.load(&b[i..]))])), &|i| vec![sb::branches(a[i], b[i])]);
        check("nested", lanes(s, |i| cols::<S, 3>(pb::nested(s, v3(&a, &b, &c, i), s.load(&f[i..])))), &|i| sb::nested(Vec3::new(a[i], b[i], c[i]), f[i]).to_array().to_vec());
        check("flags", lanes(s, |i| cols::<S, 1>([pb::flags(s, s.load(&d[i..]))])), &|i| vec![sb::flags(d[i])]);
        // Returns under masks: lanes leave at different returns.
        check("early", lanes(s, |i| cols::<S, 1>([pb::early(s, s.load(&a[i..]), s.load(&b[i..]))])), &|i| vec![sb::early(a[i], b[i])]);
        // Loops: break, continue, return inside, break if; lanes leave at different iterations.
        let small: Vec<i32> = ints.iter().map(|x| x.rem_euclid(40) - 5).collect();
        check("count_up", lanes(s, |i| cols::<S, 1>([pb::count_up(s, s.load(&a[i..]))])), &|i| vec![sb::count_up(a[i])]);
        check("skip_odd", lanes(s, |i| cols::<S, 1>([pb::skip_odd(s, s.load_i(&small[i..])).to_f32()])), &|i| vec![sb::skip_odd(small[i]) as f32]);
        check("find", lanes(s, |i| cols::<S, 1>([pb::find(s, s.load(&a[i..]) * s.splat(4.0))])), &|i| vec![sb::find(a[i] * 4.0)]);
        check("halvings", lanes(s, |i| cols::<S, 1>([pb::halvings(s, s.load(&a[i..]))])), &|i| vec![sb::halvings(a[i])]);
        // Structs: built, passed, returned, stored member-wise, blended under masks.
        check("trace", lanes(s, |i| cols::<S, 1>([pst::trace(s, v3(&a, &b, &c, i), v3(&d, &e, &f, i), s.load(&c[i..]))])), &|i| {
            vec![sst::trace(Vec3::new(a[i], b[i], c[i]), Vec3::new(d[i], e[i], f[i]), c[i])]
        });
        check("pick_ray", lanes(s, |i| cols::<S, 3>(pst::pick_ray(s, s.load(&a[i..]), v3(&d, &e, &f, i)))), &|i| sst::pick_ray(a[i], Vec3::new(d[i], e[i], f[i])).to_array().to_vec());
        // Gathers from a constant array, indices in and out of bounds.
        check("lookup", lanes(s, |i| cols::<S, 1>([pt::lookup(s, s.load(&a[i..]))])), &|i| vec![stb::lookup(a[i])]);
        // Switches: case lists, default, a break inside a case, a switch in a loop.
        check("classify", lanes(s, |i| cols::<S, 1>([pb::classify(s, s.load_i(&ints[i..]))])), &|i| vec![sb::classify(ints[i])]);
        check("switch_in_loop", lanes(s, |i| cols::<S, 1>([pb::switch_in_loop(s, s.load_i(&small[i..])).to_f32()])), &|i| vec![sb::switch_in_loop(small[i]) as f32]);
        check("early_vec", lanes(s, |i| cols::<S, 2>(pb::early_vec(s, [s.load(&a[i..]), s.load(&b[i..])]))), &|i| sb::early_vec(Vec2::new(a[i], b[i])).to_array().to_vec());
        // Guarded calls: `t` in [0, 1] and `a` in [-3, 3] send lanes to both sides; a packet
        // where no lane takes a side skips that side's calls.
        check("chosen", lanes(s, |i| cols::<S, 1>([pb::chosen(s, s.load(&a[i..]), s.load(&f[i..]))])), &|i| vec![sb::chosen(a[i], f[i])]);
        check("chosen_masked", lanes(s, |i| cols::<S, 2>(pb::chosen_masked(s, s.load(&a[i..]), s.load(&b[i..]), s.load(&f[i..])))), &|i| {
            sb::chosen_masked(a[i], b[i], f[i]).to_array().to_vec()
        });
        // All lanes on one side: the other side's calls are skipped, the result unchanged.
        let high = vec![0.9f32; N];
        check("chosen_one_side", lanes(s, |i| cols::<S, 1>([pb::chosen(s, s.load(&a[i..]), s.load(&high[i..]))])), &|i| vec![sb::chosen(a[i], 0.9)]);
        failures
    }
}

#[test]
fn packet_functions_agree_with_the_scalar_writer_on_every_level() {
    let mut failures = Vec::new();
    for level in Level::available() {
        failures.extend(level.dispatch(Compare));
    }
    let missing: Vec<&str> = Level::ALL.iter().filter(|l| !l.is_available()).map(|l| l.name()).collect();
    if !missing.is_empty() {
        eprintln!("NOT TESTED on this machine (it lacks them): SIMD levels {}", missing.join(", "));
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}
