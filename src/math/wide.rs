//! Run a numeric kernel with the widest vector instructions the CPU has (AVX2 where present,
//! chosen at run time through `pulp`'s safe dispatch; SSE2 otherwise), with the same bits.
//!
//! The crate is built for the default x86-64 target (SSE2 only) and forbids `unsafe`, so
//! its loops cannot use 4-lane `f64` vectors by themselves. A kernel handed to [`run`] is
//! compiled a second time inside a function with AVX2 enabled and that copy is called when
//! the CPU has it. The results do not depend on the copy taken: the lane order of every
//! sum is written out in the source (the vector width only maps lanes to registers), IEEE
//! add, multiply and square root round the same at any width, and Rust never fuses a
//! multiply and an add on its own.

/// A kernel: `call` must be `#[inline(always)]` (and so must what it calls), so that it is
/// compiled into the vector-enabled copy.
pub trait Kernel {
    /// What the kernel returns.
    type Output;
    /// Run the kernel.
    fn call(self) -> Self::Output;
}

struct Op<K>(K);

impl<K: Kernel> pulp::WithSimd for Op<K> {
    type Output = K::Output;
    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, _simd: S) -> K::Output {
        self.0.call()
    }
}

/// Which instruction set [`run_on`] uses.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Isa {
    /// The widest the CPU has (detected once per call; cheap, cached by `std`).
    Best,
    /// The baseline (SSE2 on x86-64): for tests that compare both.
    Baseline,
}

/// Run `k` with the widest vector instructions the CPU has.
#[inline]
pub fn run<K: Kernel>(k: K) -> K::Output {
    run_on(Isa::Best, k)
}

/// Run `k` with the instruction set `isa`.
#[inline]
pub fn run_on<K: Kernel>(isa: Isa, k: K) -> K::Output {
    match isa {
        Isa::Best => pulp::Arch::new().dispatch(Op(k)),
        Isa::Baseline => pulp::Arch::Scalar.dispatch(Op(k)),
    }
}

/// The AVX2 level of `pulp` (x86-64-v3), for kernels written with explicit vector
/// operations. Each such kernel has a scalar twin that gives the same bits: the same IEEE
/// operations in the same order, lane for lane.
#[cfg(target_arch = "x86_64")]
pub(crate) type V3 = pulp::x86::V3;

/// [`V3`] when `isa` is [`Isa::Best`] and the CPU has it (detected once, cached by `std`).
#[cfg(target_arch = "x86_64")]
#[inline]
pub(crate) fn v3(isa: Isa) -> Option<V3> {
    match isa {
        Isa::Best => V3::try_new(),
        Isa::Baseline => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    struct Sqrts<'a>(&'a [f64]);

    impl Kernel for Sqrts<'_> {
        type Output = Vec<f64>;
        #[inline(always)]
        fn call(self) -> Vec<f64> {
            self.0
                .iter()
                .map(|v| (v * v + 0.5).sqrt() * 3.0 - v)
                .collect()
        }
    }

    #[test]
    fn both_instruction_sets_give_the_same_bits() {
        let x: Vec<f64> = (0..1001).map(|k| (k as f64 * 0.37).sin() * 1e3).collect();
        let a = run_on(Isa::Best, Sqrts(&x));
        let b = run_on(Isa::Baseline, Sqrts(&x));
        assert!(a.iter().zip(&b).all(|(a, b)| a.to_bits() == b.to_bits()));
        assert_eq!(run(Sqrts(&x[..3])).len(), 3);
    }
}
