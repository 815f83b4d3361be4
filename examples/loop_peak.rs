//! Peak of the bare step loop (no escapes, no bookkeeping): V vectors of 8 lanes.
#![allow(clippy::print_stdout)] // printing the measurement is the point
use pulp::{Simd, WithSimd};

struct Job<const V: usize>(u64);
impl<const V: usize> WithSimd for Job<V> {
    type Output = f64;
    #[inline(always)]
    fn with_simd<S: Simd>(self, simd: S) -> f64 {
        let mut x = [simd.splat_f64s(0.1); V];
        let mut y = [simd.splat_f64s(0.2); V];
        let cx = [simd.splat_f64s(-0.1); V];
        let cy = [simd.splat_f64s(0.05); V];
        for _ in 0..self.0 {
            for v in 0..V {
                let yy = simd.mul_f64s(y[v], y[v]);
                let nx = simd.add_f64s(simd.mul_add_f64s(x[v], x[v], simd.neg_f64s(yy)), cx[v]);
                y[v] = simd.mul_add_f64s(simd.add_f64s(x[v], x[v]), y[v], cy[v]);
                x[v] = nx;
            }
        }
        let mut s = 0.0;
        for v in 0..V {
            s += simd.reduce_sum_f64s(x[v]) + simd.reduce_sum_f64s(y[v]);
        }
        s
    }
}

fn run<const V: usize>() {
    let steps = 50_000_000u64 / V as u64;
    let t = std::time::Instant::now();
    let s = pulp::Arch::new().dispatch(Job::<V>(steps));
    let dt = t.elapsed().as_secs_f64();
    let lane_steps = steps as f64 * V as f64 * 8.0;
    println!("V={V}: {:.2} G lane-steps/s ({s:.3})", lane_steps / dt / 1e9);
}

fn main() {
    run::<2>();
    run::<4>();
    run::<6>();
    run::<8>();
}
