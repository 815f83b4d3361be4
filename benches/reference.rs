//! Nanoseconds per reference-orbit iteration for each way deepfield can iterate it, at 1000,
//! 2000, 4000 and 16000 bits (2000: near where a helper thread starts to pay): malachite-float (pure Rust floats), fixed point on machine words
//! on one thread and shared with a helper thread (`orbit::reference::fixed`), and MPFR through rug
//! when built with `--features mpfr`.
//!
//! `cargo bench --bench reference` prints a table. Every candidate iterates the e1086
//! benchmark location's parameter (a deep minibrot: the orbit stays bounded long enough
//! and every value uses all its bits) from 0, storing nothing. Under `cargo test` it runs
//! a few iterations of each, to keep the code compiling and working.
#![allow(clippy::print_stdout)] // printing the measurement is the point

use std::time::Instant;

use deepfield::num::Decimal;
use deepfield::num::bigfloat;
use deepfield::orbit::reference::fixed::FixedOrbit;
use deepfield::simd_level::SimdLevel;
use malachite_float::Float;

const RE: &str = "-1.768610493014677074503175653270226520239677907588665494837677257575304640978808475274635707362464044253014370289948538552508877464736415873052958422861932774670165994201643419934807500290056179906392909880374230601661671965436663874506006355684166693059189687544326482526337453326360163639772818993753021740632937840115380957766425092940720439911920812397880443241274616212526380871555846532502156439892026352831619587768336768186345867565251889103622267866223055366872757385322485553606302984011695749730200727740242949661790906981449438923948817795927101980894917081591610562406554244675206099799522186446427884314773626993347929810277790888202019035845973880637832335294368222957931354735878969938534303074032237618397187328436715391758039680667871461788151793412286894565873237610467572174105629653438005433391873958639508124883860426968801537270756998560434335574379853659221182422319763412022530545421664765603500398209444536908432136868648907188939238968853841659746686717617541828417173199448336773447645561102873230388632254317334566170379314718589610910079079436175134148945650553411";
const IM: &str = "0.001266613503868717702066411192242601576193940560471409817185010171762524792588903616691501346028502452530417599269384116816237002586460261272462170615382790262110756215389780859682964779212455295242650488799024701023353984576434859496345393442867544784349509799966996827374525729583822627564832207860235000491856039278975203253540119195661182532106440194050352510825207428197675168479460252154208762204074041030502712772770772439567249008997886131809082319952112293668096363959700371035596685905429248221153089843201890985651976151989928496969024027810874574434857210174914227391125217932725188214796457327981771026544613194033736960542354861910879704489564999937473456191049937984461971508132204319961501958583967780282332682705656745932852354591955251196335374396883193221988201865629549575259395090238463522557833659758739138043696167112257784649600743807944457388512639475417466113111928274012056049434349358618953361438127758918999578120953045365596358997480091072548929426951083179599722132179281125708039705266879359303320165515458347343055671220673027817611220892213570374041225632346";

fn parameter(bits: u64) -> [Float; 2] {
    [
        bigfloat::from_decimal(&Decimal::parse(RE).expect("decimal"), bits),
        bigfloat::from_decimal(&Decimal::parse(IM).expect("decimal"), bits),
    ]
}

/// Nanoseconds per iteration of `steps` iterations of `run`.
fn time(steps: u32, run: impl FnOnce(u32)) -> f64 {
    let t = Instant::now();
    run(steps);
    t.elapsed().as_nanos() as f64 / steps as f64
}

fn main() {
    let bench = std::env::args().any(|a| a == "--bench");
    let scale = if bench { 1 } else { 1000 };
    let mut columns = vec!["malachite-float", "fixed point, 1 thread", "fixed point, 2 threads"];
    if cfg!(feature = "mpfr") {
        columns.push("MPFR (rug)");
    }
    println!(
        "| bits | iterations | {} |",
        columns.iter().map(|c| format!("{c} ns/iteration")).collect::<Vec<_>>().join(" | ")
    );
    println!("|---|---|{}", "---|".repeat(columns.len()));
    for (bits, steps) in [(1000u64, 40000u32), (2000, 20000), (4000, 10000), (16000, 1500)] {
        let steps = (steps / scale).max(2);
        let c = parameter(bits);
        let zero = || [Float::from(0u32), Float::from(0u32)];
        let mut row = Vec::new();
        row.push(time(steps, |k| {
            let mut z = zero();
            for _ in 0..k {
                bigfloat::step_assign(&mut z, &c, bits);
            }
            std::hint::black_box(&z);
        }));
        let orbit = FixedOrbit::new(&zero(), &c, bits, 65536.0, SimdLevel::detect()).expect("in range");
        row.push(time(steps, |k| {
            let mut o = orbit.clone();
            for _ in 0..k {
                o.step();
            }
            std::hint::black_box(o.get());
        }));
        row.push(time(steps, |k| {
            let mut o = orbit.clone();
            o.with_helper(|s| {
                for _ in 0..k {
                    s.step();
                }
            });
            std::hint::black_box(o.get());
        }));
        #[cfg(feature = "mpfr")]
        row.push(time(steps, |k| {
            let mut o = deepfield::orbit::reference::mpfr::MpfrOrbit::new(&zero(), &c, bits);
            for _ in 0..k {
                o.step();
            }
            std::hint::black_box(o.get());
        }));
        let cells: Vec<String> = row.iter().map(|ns| format!("{ns:.0}")).collect();
        println!("| {bits} | {steps} | {} |", cells.join(" | "));
    }
}
