//! Adam (Kingma & Ba) over a flat parameter vector, with the cosine learning-rate schedule of
//! lobes.md §4.3. The moments are part of a checkpoint, so training resumes exactly.

/// Adam's state for one parameter vector.
#[derive(Clone, Debug)]
pub struct Adam {
    pub beta1: f32,
    pub beta2: f32,
    pub eps: f32,
    pub m: Vec<f32>,
    pub v: Vec<f32>,
    /// Steps taken.
    pub t: u64,
}

impl Adam {
    pub fn new(n: usize) -> Adam {
        Adam { beta1: 0.9, beta2: 0.999, eps: 1e-8, m: vec![0.0; n], v: vec![0.0; n], t: 0 }
    }

    /// One update of `params` by `grads` at learning rate `lr`.
    pub fn step(&mut self, params: &mut [f32], grads: &[f32], lr: f32) {
        assert_eq!(params.len(), self.m.len());
        assert_eq!(grads.len(), self.m.len());
        self.t += 1;
        let c1 = 1.0 - self.beta1.powi(self.t.min(i32::MAX as u64) as i32);
        let c2 = 1.0 - self.beta2.powi(self.t.min(i32::MAX as u64) as i32);
        let (b1, b2, eps) = (self.beta1, self.beta2, self.eps);
        let step = lr / c1;
        let c2_sqrt = c2.sqrt();
        for (((p, g), m), v) in params.iter_mut().zip(grads).zip(&mut self.m).zip(&mut self.v) {
            *m = b1 * *m + (1.0 - b1) * g;
            *v = b2 * *v + (1.0 - b2) * g * g;
            *p -= step * *m / (v.sqrt() / c2_sqrt + eps);
        }
    }
}

/// Cosine decay from `lr0` at step 0 to `lr1` at `steps`.
pub fn cosine_lr(step: u64, steps: u64, lr0: f64, lr1: f64) -> f32 {
    let x = (step as f64 / steps.max(1) as f64).min(1.0);
    (lr1 + 0.5 * (lr0 - lr1) * (1.0 + (std::f64::consts::PI * x).cos())) as f32
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn adam_minimises_a_quadratic() {
        // f(p) = Σ (p_i − i)², gradient 2(p_i − i).
        let mut p = vec![0.0f32; 4];
        let mut adam = Adam::new(4);
        for step in 0..3000 {
            let g: Vec<f32> = p.iter().enumerate().map(|(i, &x)| 2.0 * (x - i as f32)).collect();
            adam.step(&mut p, &g, cosine_lr(step, 3000, 0.05, 1e-4));
        }
        for (i, x) in p.iter().enumerate() {
            assert!((x - i as f32).abs() < 1e-2, "p[{i}] = {x}");
        }
    }

    #[test]
    fn cosine_schedule_ends() {
        assert_eq!(cosine_lr(0, 100, 1e-3, 1e-5), 1e-3);
        assert!((cosine_lr(100, 100, 1e-3, 1e-5) - 1e-5).abs() < 1e-9);
        assert!((cosine_lr(50, 100, 1e-3, 1e-5) - 0.505e-3).abs() < 1e-7);
    }
}
