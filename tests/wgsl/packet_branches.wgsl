// Varying `if`s for the packet writer (both sides under masks, stores blended): written as packet
// Rust (tests/out/packet/) and by the scalar writer (the oracle), compared lane by lane in
// tests/rs_compile/tests/integration/packet_vs_scalar.rs on inputs where lanes take different sides.
fn branches(a: f32, b: f32) -> f32 {
    var r = b;
    if (a > 0.0) {
        r = a * 2.0;
    } else {
        if (b < 0.0) {
            r = -b;
        }
    }
    return r;
}
fn nested(v: vec3<f32>, t: f32) -> vec3<f32> {
    var out = v;
    var k = 0;
    if (t > 0.5) {
        out = out * t;
        k = 2;
        if (v.x < 0.0) {
            out.y = 7.0;
            k = k + 1;
        }
    } else {
        out = vec3(t);
    }
    return out + vec3(f32(k));
}
fn flags(a: f32) -> f32 {
    var hit = false;
    var n = 0u;
    if (abs(a) < 1.0) {
        hit = true;
        n = 5u;
    }
    return select(0.5, 1.5, hit) + f32(n);
}
fn early(a: f32, b: f32) -> f32 {
    if (a > 1.0) {
        return a;
    }
    if (b > 0.0) {
        if (a < -1.0) {
            return -10.0;
        }
        return b * 3.0;
    }
    return a + b;
}
fn early_vec(v: vec2<f32>) -> vec2<f32> {
    if (v.x > v.y) {
        return v.yx;
    }
    return v * 2.0;
}
// Loops: lanes leave at different iterations (break, continue, return, break if).
fn count_up(x: f32) -> f32 {
    var acc = 0.0;
    for (var i = 0; i < 8; i++) {
        if (f32(i) > x * 3.0) {
            break;
        }
        acc += 1.5;
    }
    return acc;
}
fn skip_odd(n: i32) -> i32 {
    var total = 0;
    var i = 0;
    loop {
        if (i >= n) {
            break;
        }
        i++;
        if (i % 2 == 1) {
            continue;
        }
        total += i;
    }
    return total;
}
fn find(x: f32) -> f32 {
    var v = x;
    for (var k = 0; k < 10; k++) {
        v = v * 0.5 + 1.0;
        if (v < 2.1) {
            return f32(k);
        }
    }
    return -1.0;
}
fn halvings(x: f32) -> f32 {
    var t = abs(x) + 0.2;
    var n = 0.0;
    loop {
        t = t * 0.7;
        n += 1.0;
        continuing {
            break if t < 0.1;
        }
    }
    return n;
}
// Switch on a varying selector: case lists, default, a break ending a case, a switch in a loop
// with continue.
fn classify(n: i32) -> f32 {
    var r = 0.0;
    switch (n % 5) {
        case 0, 1: {
            r = 10.0;
        }
        case 2: {
            if (n > 20) {
                r = -1.0;
                break;
            }
            r = 20.0;
        }
        case -3: {
            return 99.0;
        }
        default: {
            r = f32(n) * 0.5;
        }
    }
    return r + 1.0;
}
fn switch_in_loop(n: i32) -> i32 {
    var total = 0;
    for (var i = 0; i < n; i++) {
        switch (i % 3) {
            case 0: {
                continue;
            }
            case 1: {
                total += i;
            }
            default: {
                total += 100;
                break;
            }
        }
        total += 1;
    }
    return total;
}
// Guarded calls (compiler/src/packet_guards.rs): each call feeds one side of a select, through
// an expression or another call, and runs only where some lane takes that side; the condition
// is written at the call although WGSL computes it after.
fn dear(x: f32) -> f32 {
    var a = x;
    for (var i = 0; i < 4; i++) {
        a = a * 0.5 + sin(a);
    }
    return a;
}
fn cheap(x: f32) -> f32 {
    return x * x;
}
fn chosen(a: f32, t: f32) -> f32 {
    return select(cheap(a), 2.0 * dear(cheap(a + 1.0)), t > 0.5) + select(dear(a), 1.0, a < -2.5);
}
fn chosen_masked(a: f32, b: f32, t: f32) -> vec2<f32> {
    var r = vec2(b, 0.0);
    if (b > 0.0) {
        r = select(vec2(cheap(a)), vec2(dear(b), t), (t > 0.25) & (a < 1.0));
    }
    return r;
}
