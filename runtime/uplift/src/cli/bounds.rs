//! The documented upper bounds of the command line's sizes, counts, sample counts, steps and
//! frames (issue 46): one table, read by clap's value parsers, so an argument past its bound is
//! refused before anything is allocated ("invalid value '100000' for '--size <SIZE>': 100000 is
//! not in 1..=8192", exit 2) and `uplift <command> --help` and docs/cli.md say the same.
//! A bound is set where the largest allocation it drives stays within a workstation's memory
//! (an 8192² image's radiance, accumulator and output are ≈ 1.6 GB) or where a run would
//! otherwise take longer than anyone would wait for it by mistake.

use clap::builder::RangedU64ValueParser;

/// One bounded kind of argument: its largest value and why.
pub struct Bound {
    pub min: u64,
    pub max: u64,
    /// What the bound limits, as `--help` and docs/cli.md say it.
    pub what: &'static str,
}

/// Image width / height in pixels (`render`, `eval-fit`, `export`, `gallery`, `demo`).
pub const IMAGE_SIDE: Bound = Bound { min: 1, max: 8192, what: "pixels a side (an 8192² rendering holds ≈ 1.6 GB)" };
/// Samples per pixel.
pub const SPP: Bound = Bound { min: 1, max: 1 << 16, what: "samples per pixel" };
/// Path bounces.
pub const BOUNCES: Bound = Bound { min: 0, max: 64, what: "surface interactions after the first" };
/// Frames of an exported orbit.
pub const FRAMES: Bound = Bound { min: 1, max: 4096, what: "frames" };
/// Texels a side of a baked or projected texture and of a mask.
pub const TEXTURE_SIDE: Bound = Bound { min: 1, max: 16384, what: "texels a side (a 16384² float texture holds 1 GiB a channel)" };
/// Texels a side of a bake or projection (`project --resolution`; `enhance --resolution WxH`
/// per side).
pub const BAKE_SIDE: Bound = Bound { min: 1, max: 8192, what: "texels a side of a bake" };
/// Optimiser steps (`train`, `train-sampler`, `fit`).
pub const STEPS: Bound = Bound { min: 1, max: 100_000_000, what: "optimiser steps" };
/// Rows of one training batch.
pub const BATCH: Bound = Bound { min: 1, max: 1 << 24, what: "rows a batch" };
/// Light directions per view.
pub const DIRECTIONS_PER_VIEW: Bound = Bound { min: 1, max: 16384, what: "directions per view" };
/// Views (`furnace`, `train-sampler`).
pub const VIEWS: Bound = Bound { min: 1, max: 1 << 20, what: "views" };
/// Rows `datagen` writes: 2^40 (≈ 10^12 rows, hundreds of terabytes of shards); its shard list
/// is bounded by [`SHARDS`] too.
pub const ROWS: Bound = Bound { min: 1, max: 1 << 40, what: "rows" };
/// Rows a `datagen` shard holds (its tensors are built in memory: ≈ 1 GB at 2^22 rows).
pub const SHARD_ROWS: Bound = Bound { min: 1, max: 1 << 22, what: "rows a shard" };
/// Shards one `datagen` run writes (`--count / --shard-rows`, rounded up).
pub const SHARDS: Bound = Bound { min: 1, max: 1 << 20, what: "shards" };

/// Every bound, by the flags that take it (docs/cli.md is checked against this table).
#[cfg(test)]
pub const TABLE: &[(&str, &Bound)] = &[
    ("--size (render, eval-fit, export, gallery), --render-size (demo)", &IMAGE_SIDE),
    ("--spp", &SPP),
    ("--bounces", &BOUNCES),
    ("--frames (export)", &FRAMES),
    ("--size (masks), --mask-size (enhance)", &TEXTURE_SIDE),
    ("--resolution (project; enhance's WxH per side)", &BAKE_SIDE),
    ("--steps (train, train-sampler, fit)", &STEPS),
    ("--batch (train)", &BATCH),
    ("--directions-per-view (datagen, train), --directions (fit)", &DIRECTIONS_PER_VIEW),
    ("--views (furnace, train-sampler)", &VIEWS),
    ("--count (datagen)", &ROWS),
    ("--shard-rows (datagen)", &SHARD_ROWS),
    ("--count / --shard-rows (datagen)", &SHARDS),
];

/// The row of docs/cli.md's table of bounds for `flags`.
#[cfg(test)]
pub fn doc_row(flags: &str, bound: &Bound) -> String {
    format!("| {flags} | {} to {} | {} |", bound.min, bound.max, bound.what)
}

impl Bound {
    /// A clap value parser for min..=max into `T` (usize or u64).
    pub fn parser<T>(&self) -> RangedU64ValueParser<T>
    where
        T: TryFrom<u64> + Clone + Send + Sync + 'static,
        <T as TryFrom<u64>>::Error: std::error::Error + Send + Sync + 'static,
    {
        RangedU64ValueParser::<T>::new().range(self.min..=self.max)
    }

    /// Checks a value that is not a flag of its own (`WxH`, a quotient): min..=max, or an error
    /// naming `flag`.
    pub fn check(&self, flag: &str, value: u64) -> Result<(), String> {
        match (self.min..=self.max).contains(&value) {
            true => Ok(()),
            false => Err(format!("{flag}: {value} is not in {}..={} ({})", self.min, self.max, self.what)),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_bound_accepts_its_range_and_names_the_flag_outside_it() {
        assert!(IMAGE_SIDE.check("--size", 8192).is_ok());
        let e = IMAGE_SIDE.check("--size", 100_000).unwrap_err();
        assert_eq!(e, "--size: 100000 is not in 1..=8192 (pixels a side (an 8192² rendering holds ≈ 1.6 GB))");
        assert!(SPP.check("--spp", 0).is_err());
        assert!(BOUNCES.check("--bounces", 0).is_ok());
    }

    /// docs/cli.md's table of bounds is this table (a row per entry, as [`doc_row`] writes it).
    #[test]
    fn docs_cli_md_lists_every_bound() {
        let doc = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../../docs/cli.md")).unwrap();
        for (flags, bound) in TABLE {
            let row = doc_row(flags, bound);
            assert!(doc.contains(&row), "docs/cli.md lacks the row\n{row}");
        }
    }

    #[test]
    fn the_parser_refuses_past_the_bound_and_zero() {
        let cmd = clap::Command::new("t").arg(clap::Arg::new("size").long("size").value_parser(IMAGE_SIDE.parser::<usize>()));
        assert_eq!(*cmd.clone().try_get_matches_from(["t", "--size", "8192"]).unwrap().get_one::<usize>("size").unwrap(), 8192);
        for bad in ["100000", "0", "18446744073709551615", "-1"] {
            let e = cmd.clone().try_get_matches_from(["t", "--size", bad]).unwrap_err().to_string();
            assert!(e.contains(&format!("invalid value '{bad}'")), "{bad}: {e}");
        }
    }
}
