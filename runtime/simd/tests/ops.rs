//! Every operation of the SIMD layer, on every level this machine has (and `Emu<16>`, `Emu<1>`
//! everywhere), against scalar Rust over a grid of special values (±0, ±∞, NaN, subnormals,
//! ±2³¹, 2³², halfway rounding cases, `i32::MIN`, shift amounts ≥ 32, zero divisors) and seeded
//! random values (uniform numbers and random bit patterns). Results must be bit-identical
//! (any NaN matches any NaN), except: `min`/`max` may return either zero for (+0, −0), where
//! Rust's `f32::min` leaves the sign unspecified; `rcp`/`rsqrt` within 2 ulp for normal inputs
//! (exact at ±0 and ±∞; a subnormal input may act as zero); `mul_add` is compared with the
//! fused `f32::mul_add` on hardware levels and with `a·b + c` on `Emu` (the crate's contract).

use uplift_simd::{F32s, I32s, Level, M32s, Simd, U32s, WithSimd};

const COUNT: usize = 1024;

struct Rng(u64);
impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        self.0
    }
}

fn float_inputs(seed: u64) -> Vec<f32> {
    let special = [
        0.0, -0.0, 1.0, -1.0, 0.5, -0.5, 1.5, -1.5, 2.5, -2.5, 3.5, 0.49999997, -0.49999997, 8388607.5, -8388607.5, 8388608.0,
        f32::MIN_POSITIVE, -f32::MIN_POSITIVE, 1e-40, -1e-40, 1e-45, f32::MAX, -f32::MAX, f32::INFINITY, f32::NEG_INFINITY, f32::NAN,
        -f32::NAN, 2147483520.0, 2147483648.0, -2147483648.0, -2147483904.0, 4294967040.0, 4294967296.0, 1e10, -1e10, 3.0, 1e-30,
        123.456, -0.75, 65536.0, 16777217.0, 0.1,
    ];
    let mut rng = Rng(seed);
    let mut v: Vec<f32> = special.to_vec();
    while v.len() < COUNT {
        let r = rng.next();
        v.push(if r & 3 == 0 { f32::from_bits((r >> 32) as u32) } else { ((r >> 40) as f32 / (1u64 << 24) as f32) * 8.0 - 4.0 });
    }
    v
}

fn int_inputs(seed: u64) -> Vec<i32> {
    let special = [0, 1, -1, 2, -2, 7, -7, 31, 32, 33, 63, -32, i32::MIN, i32::MAX, i32::MIN + 1, 0xFFFF, 0x10000, -65536, 3, 100];
    let mut rng = Rng(seed);
    let mut v: Vec<i32> = special.to_vec();
    while v.len() < COUNT {
        let r = rng.next();
        v.push(if r & 1 == 0 { (r >> 32) as i32 } else { ((r >> 32) % 80) as i32 - 40 });
    }
    v
}

/// `b` rotated so that every special value meets others.
fn rotated<T: Copy>(a: &[T], by: usize) -> Vec<T> {
    (0..a.len()).map(|k| a[(k + by) % a.len()]).collect()
}

fn same(x: f32, y: f32) -> bool {
    (x.is_nan() && y.is_nan()) || x.to_bits() == y.to_bits()
}

fn ulps(x: f32, y: f32) -> u32 {
    if x.is_sign_negative() != y.is_sign_negative() {
        return u32::MAX;
    }
    x.to_bits().abs_diff(y.to_bits())
}

struct Checker {
    level: &'static str,
    failures: Vec<String>,
}

impl Checker {
    fn fail(&mut self, what: String) {
        if self.failures.len() < 40 {
            self.failures.push(format!("{}: {what}", self.level));
        }
    }
}

/// Runs a packet operation over index chunks; `lane(k)` reads result lane `k` of the chunk.
fn chunks<S: Simd, R>(s: S, n: usize, mut f: impl FnMut(usize) -> R, mut each: impl FnMut(usize, &R)) {
    let _ = s;
    for start in (0..n).step_by(S::LANES) {
        let r = f(start);
        each(start, &r);
    }
}

fn floats<S: Simd>(v: S::F) -> Vec<f32> {
    let mut out = vec![0.0; S::LANES];
    v.write_to(&mut out);
    out
}
fn ints<S: Simd>(v: S::I) -> Vec<i32> {
    let mut out = vec![0; S::LANES];
    v.write_to(&mut out);
    out
}
fn uints<S: Simd>(v: S::U) -> Vec<u32> {
    let mut out = vec![0; S::LANES];
    v.write_to(&mut out);
    out
}
fn bits<S: Simd>(m: S::M) -> Vec<bool> {
    let b = m.bitmask();
    (0..S::LANES).map(|k| b >> k & 1 == 1).collect()
}

struct AllOps;

impl WithSimd for AllOps {
    type Output = Vec<String>;
    #[inline(always)]
    fn with_simd<S: Simd>(self, s: S) -> Vec<String> {
        let mut c = Checker { level: S::NAME, failures: Vec::new() };
        float_ops(s, &mut c);
        int_ops(s, &mut c);
        uint_ops(s, &mut c);
        memory_ops(s, &mut c);
        c.failures
    }
}

fn float_ops<S: Simd>(s: S, c: &mut Checker) {
    let a = float_inputs(1);
    let b = rotated(&a, 7);
    let d = rotated(&a, 19);
    let hardware = !S::NAME.starts_with("emu") && S::NAME != "scalar";
    type Unary<S> = (&'static str, fn(<S as Simd>::F) -> <S as Simd>::F, fn(f32) -> f32);
    let unary: Vec<Unary<S>> = vec![
        ("neg", |x| -x, |x| -x),
        ("abs", |x| x.abs(), f32::abs),
        ("sqrt", |x| x.sqrt(), f32::sqrt),
        ("floor", |x| x.floor(), f32::floor),
        ("ceil", |x| x.ceil(), f32::ceil),
        ("trunc", |x| x.trunc(), f32::trunc),
        ("round", |x| x.round(), f32::round_ties_even),
        ("fract", |x| x.fract(), |x| x - x.floor()),
        ("map(sin)", |x| x.map(f32::sin), f32::sin),
    ];
    for (name, op, reference) in unary {
        chunks(s, COUNT, |i| floats::<S>(op(s.load(&a[i..]))), |i, r| {
            for (k, &y) in r.iter().enumerate() {
                let want = reference(a[i + k]);
                if !same(y, want) {
                    c.fail(format!("{name}({:e}) = {y:e}, want {want:e}", a[i + k]));
                }
            }
        });
    }
    type Binary<S> = (&'static str, fn(<S as Simd>::F, <S as Simd>::F) -> <S as Simd>::F, fn(f32, f32) -> f32);
    let binary: Vec<Binary<S>> = vec![
        ("add", |x, y| x + y, |x, y| x + y),
        ("sub", |x, y| x - y, |x, y| x - y),
        ("mul", |x, y| x * y, |x, y| x * y),
        ("div", |x, y| x / y, |x, y| x / y),
        ("min", |x, y| x.min(y), f32::min),
        ("max", |x, y| x.max(y), f32::max),
    ];
    for (name, op, reference) in binary {
        chunks(s, COUNT, |i| floats::<S>(op(s.load(&a[i..]), s.load(&b[i..]))), |i, r| {
            for (k, &y) in r.iter().enumerate() {
                let (p, q) = (a[i + k], b[i + k]);
                let want = reference(p, q);
                let zeros = (name == "min" || name == "max") && p == 0.0 && q == 0.0 && y == 0.0;
                if !same(y, want) && !zeros {
                    c.fail(format!("{name}({p:e}, {q:e}) = {y:e}, want {want:e}"));
                }
            }
        });
    }
    chunks(s, COUNT, |i| floats::<S>(s.load(&a[i..]).mul_add(s.load(&b[i..]), s.load(&d[i..]))), |i, r| {
        for (k, &y) in r.iter().enumerate() {
            let (p, q, t) = (a[i + k], b[i + k], d[i + k]);
            let want = if hardware { p.mul_add(q, t) } else { p * q + t };
            if !same(y, want) {
                c.fail(format!("mul_add({p:e}, {q:e}, {t:e}) = {y:e}, want {want:e}"));
            }
        }
    });
    type Approx<S> = (&'static str, fn(<S as Simd>::F) -> <S as Simd>::F, fn(f32) -> f32);
    let approx: Vec<Approx<S>> = vec![("rcp", |x| x.rcp(), |x| 1.0 / x), ("rsqrt", |x| x.rsqrt(), |x| 1.0 / x.sqrt())];
    for (name, op, reference) in approx {
        chunks(s, COUNT, |i| floats::<S>(op(s.load(&a[i..]))), |i, r| {
            for (k, &y) in r.iter().enumerate() {
                let x = a[i + k];
                let want = reference(x);
                let ok = if x.is_subnormal() {
                    same(y, reference(0.0f32.copysign(x))) || same(y, want) || ulps(y, want) <= 2
                } else if x.is_nan() || want.is_nan() {
                    y.is_nan() && want.is_nan()
                } else if x == 0.0 || x.is_infinite() {
                    same(y, want)
                } else if want.is_subnormal() || want == 0.0 {
                    // 1/x below the normal range: flushing to zero is allowed.
                    y.abs() <= f32::MIN_POSITIVE && y.is_sign_negative() == want.is_sign_negative()
                } else {
                    ulps(y, want) <= 2
                };
                if !ok {
                    c.fail(format!("{name}({x:e}) = {y:e}, want {want:e} ±2 ulp"));
                }
            }
        });
    }
    type Compare<S> = (&'static str, fn(<S as Simd>::F, <S as Simd>::F) -> <S as Simd>::M, fn(f32, f32) -> bool);
    let compares: Vec<Compare<S>> = vec![
        ("eq", |x, y| x.eq(y), |x, y| x == y),
        ("ne", |x, y| x.ne(y), |x, y| x != y),
        ("lt", |x, y| x.lt(y), |x, y| x < y),
        ("le", |x, y| x.le(y), |x, y| x <= y),
        ("gt", |x, y| x.gt(y), |x, y| x > y),
        ("ge", |x, y| x.ge(y), |x, y| x >= y),
        ("is_nan", |x, _| x.is_nan(), |x, _| x.is_nan()),
    ];
    for (name, op, reference) in compares {
        // Compare a value with itself too (b = a for the first third of the chunks).
        let b2: Vec<f32> = (0..COUNT).map(|k| if k < COUNT / 3 { a[k] } else { b[k] }).collect();
        chunks(s, COUNT, |i| op(s.load(&a[i..]), s.load(&b2[i..])), |i, m| {
            let got = bits::<S>(*m);
            for (k, &g) in got.iter().enumerate() {
                let want = reference(a[i + k], b2[i + k]);
                if g != want {
                    c.fail(format!("{name}({:e}, {:e}) = {g}, want {want}", a[i + k], b2[i + k]));
                }
            }
            let (any, all) = (m.any(), m.all());
            if any != got.iter().any(|&x| x) || all != got.iter().all(|&x| x) {
                c.fail(format!("any/all of {got:?} = {any}/{all}"));
            }
            // Mask algebra and selects against the lanes.
            let other = s.load(&b[i..]).lt(s.load(&d[i..]));
            let ob = bits::<S>(other);
            let and = bits::<S>(*m & other);
            let or = bits::<S>(*m | other);
            let xor = bits::<S>(*m ^ other);
            let not = bits::<S>(!*m);
            for k in 0..S::LANES {
                if and[k] != (got[k] & ob[k]) || or[k] != (got[k] | ob[k]) || xor[k] != (got[k] ^ ob[k]) || not[k] == got[k] {
                    c.fail(format!("mask algebra at lane {k}"));
                }
            }
            let sel = floats::<S>(m.select(s.load(&a[i..]), s.load(&d[i..])));
            let sel_i = ints::<S>(m.select_i(s.splat_i(1), s.splat_i(-2)));
            let sel_u = uints::<S>(m.select_u(s.splat_u(u32::MAX), s.splat_u(3)));
            for k in 0..S::LANES {
                let want = if got[k] { a[i + k] } else { d[i + k] };
                if !same(sel[k], want) || sel_i[k] != if got[k] { 1 } else { -2 } || sel_u[k] != if got[k] { u32::MAX } else { 3 } {
                    c.fail(format!("select at lane {k} of mask {got:?}"));
                }
            }
        });
    }
    chunks(s, COUNT, |i| (ints::<S>(s.load(&a[i..]).to_i32()), uints::<S>(s.load(&a[i..]).to_u32()), uints::<S>(s.load(&a[i..]).to_bits())), |i, (si, su, sb)| {
        for k in 0..S::LANES {
            let x = a[i + k];
            if si[k] != x as i32 || su[k] != x as u32 || sb[k] != x.to_bits() {
                c.fail(format!("conversions of {x:e}: i32 {} (want {}), u32 {} (want {}), bits {:#x}", si[k], x as i32, su[k], x as u32, sb[k]));
            }
        }
    });
}

fn int_ops<S: Simd>(s: S, c: &mut Checker) {
    let a = int_inputs(2);
    let b = rotated(&a, 5);
    type Binary<S> = (&'static str, fn(<S as Simd>::I, <S as Simd>::I) -> <S as Simd>::I, fn(i32, i32) -> i32);
    let binary: Vec<Binary<S>> = vec![
        ("add", |x, y| x + y, i32::wrapping_add),
        ("sub", |x, y| x - y, i32::wrapping_sub),
        ("mul", |x, y| x * y, i32::wrapping_mul),
        ("and", |x, y| x & y, |x, y| x & y),
        ("or", |x, y| x | y, |x, y| x | y),
        ("xor", |x, y| x ^ y, |x, y| x ^ y),
        ("shl", |x, y| x.shl(y), |x, y| x.wrapping_shl(y as u32)),
        ("shr", |x, y| x.shr(y), |x, y| x.wrapping_shr(y as u32)),
        ("div", |x, y| x.div(y), |x, y| x.checked_div(y).unwrap_or(x)),
        ("rem", |x, y| x.rem(y), |x, y| x.checked_rem(y).unwrap_or(0)),
        ("min", |x, y| x.min(y), Ord::min),
        ("max", |x, y| x.max(y), Ord::max),
        ("neg", |x, _| -x, |x, _| x.wrapping_neg()),
        ("not", |x, _| !x, |x, _| !x),
        ("abs", |x, _| x.abs(), |x, _| x.wrapping_abs()),
        ("eq", |x, y| x.eq(y).select_i(x, y), |x, y| if x == y { x } else { y }),
        ("lt", |x, y| x.lt(y).select_i(x, y), |x, y| if x < y { x } else { y }),
        ("gt", |x, y| x.gt(y).select_i(x, y), |x, y| if x > y { x } else { y }),
        ("bits", |x, _| x.to_u32_bits().to_i32_bits(), |x, _| x),
    ];
    for (name, op, reference) in binary {
        chunks(s, COUNT, |i| ints::<S>(op(s.load_i(&a[i..]), s.load_i(&b[i..]))), |i, r| {
            for (k, &y) in r.iter().enumerate() {
                let want = reference(a[i + k], b[i + k]);
                if y != want {
                    c.fail(format!("i32 {name}({}, {}) = {y}, want {want}", a[i + k], b[i + k]));
                }
            }
        });
    }
    chunks(s, COUNT, |i| floats::<S>(s.load_i(&a[i..]).to_f32()), |i, r| {
        for (k, &y) in r.iter().enumerate() {
            if !same(y, a[i + k] as f32) {
                c.fail(format!("i32 to_f32({}) = {y}", a[i + k]));
            }
        }
    });
}

fn uint_ops<S: Simd>(s: S, c: &mut Checker) {
    let a: Vec<u32> = int_inputs(3).into_iter().map(|x| x as u32).collect();
    let b = rotated(&a, 11);
    type Binary<S> = (&'static str, fn(<S as Simd>::U, <S as Simd>::U) -> <S as Simd>::U, fn(u32, u32) -> u32);
    let binary: Vec<Binary<S>> = vec![
        ("add", |x, y| x + y, u32::wrapping_add),
        ("sub", |x, y| x - y, u32::wrapping_sub),
        ("mul", |x, y| x * y, u32::wrapping_mul),
        ("and", |x, y| x & y, |x, y| x & y),
        ("or", |x, y| x | y, |x, y| x | y),
        ("xor", |x, y| x ^ y, |x, y| x ^ y),
        ("not", |x, _| !x, |x, _| !x),
        ("shl", |x, y| x.shl(y), u32::wrapping_shl),
        ("shr", |x, y| x.shr(y), u32::wrapping_shr),
        ("div", |x, y| x.div(y), |x, y| x.checked_div(y).unwrap_or(x)),
        ("rem", |x, y| x.rem(y), |x, y| x.checked_rem(y).unwrap_or(0)),
        ("min", |x, y| x.min(y), Ord::min),
        ("max", |x, y| x.max(y), Ord::max),
        ("eq", |x, y| x.eq(y).select_u(x, y), |x, y| if x == y { x } else { y }),
        ("lt", |x, y| x.lt(y).select_u(x, y), |x, y| if x < y { x } else { y }),
        ("gt", |x, y| x.gt(y).select_u(x, y), |x, y| if x > y { x } else { y }),
        ("bits", |x, _| x.to_f32_bits().to_bits(), |x, _| x),
    ];
    for (name, op, reference) in binary {
        chunks(s, COUNT, |i| uints::<S>(op(s.load_u(&a[i..]), s.load_u(&b[i..]))), |i, r| {
            for (k, &y) in r.iter().enumerate() {
                let want = reference(a[i + k], b[i + k]);
                if y != want {
                    c.fail(format!("u32 {name}({}, {}) = {y}, want {want}", a[i + k], b[i + k]));
                }
            }
        });
    }
    chunks(s, COUNT, |i| floats::<S>(s.load_u(&a[i..]).to_f32()), |i, r| {
        for (k, &y) in r.iter().enumerate() {
            if !same(y, a[i + k] as f32) {
                c.fail(format!("u32 to_f32({}) = {y}, want {}", a[i + k], a[i + k] as f32));
            }
        }
    });
}

fn memory_ops<S: Simd>(s: S, c: &mut Checker) {
    let n = S::LANES;
    let values: Vec<f32> = (0..n).map(|k| k as f32 + 0.5).collect();
    for len in 0..=n {
        let got = floats::<S>(s.load_partial(&values[..len]));
        let mut out = vec![-1.0; len];
        s.store_partial(s.load(&values), &mut out);
        let mask = bits::<S>(s.first_lanes(len));
        for k in 0..n {
            let want = if k < len { values[k] } else { 0.0 };
            if !same(got[k], want) || mask[k] != (k < len) {
                c.fail(format!("load_partial/first_lanes of {len} at lane {k}"));
            }
        }
        if out != values[..len] {
            c.fail(format!("store_partial of {len}: {out:?}"));
        }
    }
    if ints::<S>(s.lane_index()) != (0..n as i32).collect::<Vec<_>>() {
        c.fail("lane_index".into());
    }
    let table: Vec<f32> = (0..37).map(|k| (k * k) as f32).collect();
    let idx: Vec<i32> = int_inputs(4).iter().map(|x| x % 50).collect();
    chunks(s, COUNT, |i| floats::<S>(s.gather(&table, s.load_i(&idx[i..]))), |i, r| {
        for (k, &y) in r.iter().enumerate() {
            let want = table[idx[i + k].clamp(0, 36) as usize];
            if y != want {
                c.fail(format!("gather at index {} = {y}, want {want}", idx[i + k]));
            }
        }
    });
    let single = [42.0f32];
    if floats::<S>(s.gather(&single, s.lane_index() - s.splat_i(3))).iter().any(|&y| y != 42.0) {
        c.fail("gather from a one-value table".into());
    }
}

#[test]
fn every_operation_matches_scalar_rust_on_every_level_here() {
    let mut failures = Vec::new();
    for level in Level::available() {
        failures.extend(level.dispatch(AllOps));
    }
    // Odd widths run the same generic code.
    failures.extend(AllOps.with_simd(uplift_simd::Emu::<4>));
    let missing: Vec<&str> = Level::ALL.iter().filter(|l| !l.is_available()).map(|l| l.name()).collect();
    if !missing.is_empty() {
        eprintln!("NOT TESTED on this machine (it lacks them): SIMD levels {}", missing.join(", "));
    }
    assert!(failures.is_empty(), "{} failure(s):\n{}", failures.len(), failures.join("\n"));
}

/// The lanes of the level it runs at.
struct Lanes;

impl WithSimd for Lanes {
    type Output = usize;
    #[inline(always)]
    fn with_simd<S: Simd>(self, _: S) -> usize {
        S::LANES
    }
}

#[test]
fn dispatch_runs_the_widest_level_and_refuses_a_missing_one() {
    let best = Level::detect();
    assert_eq!(best.dispatch(Lanes), best.lanes());
    for level in Level::ALL {
        if level.is_available() {
            assert_eq!(level.dispatch(Lanes), level.lanes(), "{}", level.name());
        } else {
            assert!(std::panic::catch_unwind(|| level.dispatch(Lanes)).is_err(), "{} ran without its features", level.name());
        }
    }
}

#[test]
fn outlined_code_computes_what_inlined_code_does_and_run_hardware_picks_the_current_level() {
    struct Outlined;
    impl WithSimd for Outlined {
        type Output = Vec<f32>;
        #[inline(always)]
        fn with_simd<S: Simd>(self, s: S) -> Vec<f32> {
            let x = s.load(&[0.5, -1.5, 2.0, 3.25, 0.0, 7.0, -2.0, 1.0, 9.0, 4.0, -3.0, 5.5, 6.0, 0.25, 8.0, -0.5][..S::LANES]);
            // A captured packet, a result through the outlined function, and a nested one.
            let y = s.outline(#[inline(always)] || x * x + s.outline(#[inline(always)] || x.sqrt().max(s.splat(-1.0))));
            floats::<S>(y)
        }
    }
    let want = |x: f32| x * x + x.sqrt().max(-1.0);
    for level in Level::available() {
        let got = level.dispatch(Outlined);
        let xs = [0.5f32, -1.5, 2.0, 3.25, 0.0, 7.0, -2.0, 1.0, 9.0, 4.0, -3.0, 5.5, 6.0, 0.25, 8.0, -0.5];
        for (k, g) in got.iter().enumerate() {
            assert!(same(*g, want(xs[k])), "{} lane {k}: {g} vs {}", level.name(), want(xs[k]));
        }
    }
    match Level::current() {
        Level::Scalar => assert_eq!(Level::run_hardware(Lanes), None),
        l => assert_eq!(Level::run_hardware(Lanes), Some(l.lanes())),
    }
}
