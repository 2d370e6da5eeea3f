//! `rayterm merge`: the partial films of a split render into the image one
//! render of all their samples makes, post-processed as `render` does; or
//! into one partial film that merges again with the parts still to come.

use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Instant;

use anyhow::{bail, Result};
use clap::Parser;

use super::args::{Cli, Command, MergeArgs};
use super::render::{image_bytes, summary};
use crate::interrupt::{self, Cancel};
use crate::raster::{ImageFormat, Output};
use crate::render::partial::{self, ranges_text, MergePlan, Meta};
use crate::render::SceneRequest;
use crate::words;

pub(crate) fn run(a: MergeArgs) -> Result<ExitCode> {
    let formats = match a.partial {
        true => &[ImageFormat::Exr][..],
        false => ImageFormat::RENDERS,
    };
    let out = Output::check(&a.output, &a.parts, formats)?;
    interrupt::flag();
    let cancel = Cancel::Signal;
    let start = Instant::now();
    let plan = partial::plan(&a.parts)?;
    if let Some(spec) = &a.check {
        check(spec, &plan)?;
    }
    let count = plan.parts.len();
    if !plan.missing.is_empty() && !a.partial {
        let what = missing(&plan);
        if !a.allow_missing {
            bail!(
                "{what}: render {}\nor merge what there is with --allow-missing",
                to_render(&plan)
            );
        }
        let held: u32 = plan.parts.iter().map(|(_, h)| h.range.len() as u32).sum();
        crate::noteln!(
            "warning: {what}: the image has {held} of {} spp",
            plan.total
        );
    }
    if a.partial {
        return staged(&plan, &out, cancel, start);
    }
    let merged = partial::merge(&plan, cancel);
    if cancel.is_set() {
        crate::noteln!("interrupted: nothing written");
        return Ok(ExitCode::from(interrupt::exit_code()));
    }
    let merged = merged?;
    let (meta, (width, height)) = (&merged.meta, merged.size);
    let bytes = image_bytes(out.format, merged.image, width, height, meta.bloom.as_ref())?;
    if !write(&out, &bytes, cancel)? {
        return Ok(ExitCode::from(interrupt::exit_code()));
    }
    let head = format!(
        "{}: {}, merged {} in {}, render {} in all",
        meta.scene,
        words::count(meta.triangles, "triangle", "triangles"),
        words::count(count as u64, "part", "parts"),
        words::ms(start.elapsed().as_secs_f64() * 1e3),
        words::ms(meta.seconds * 1e3)
    );
    let mut line = summary(
        &head,
        &merged.report,
        false,
        meta.rays,
        meta.seconds * 1e3,
        meta.exact,
        "",
        &a.output,
    );
    if !plan.missing.is_empty() {
        line = line.replacen(" spp,", " spp (samples missing),", 1);
    }
    say(&out, &line)
}

/// `merge --partial`: the parts as one partial film.
fn staged(plan: &MergePlan, out: &Output, cancel: Cancel, start: Instant) -> Result<ExitCode> {
    let part = partial::merge_part(plan, cancel);
    if cancel.is_set() {
        crate::noteln!("interrupted: nothing written");
        return Ok(ExitCode::from(interrupt::exit_code()));
    }
    let part = part?;
    let bytes = partial::encode(&part.film, &part.meta)?;
    if !write(out, &bytes, cancel)? {
        return Ok(ExitCode::from(interrupt::exit_code()));
    }
    let r = part.range();
    let mut line = format!(
        "{}: merged {} in {} into samples {}..{} -> {}",
        part.meta.scene,
        words::count(plan.parts.len() as u64, "part", "parts"),
        words::ms(start.elapsed().as_secs_f64() * 1e3),
        r.start,
        r.end,
        words::path(&out.path)
    );
    if !plan.missing.is_empty() {
        line += &format!("; still to merge with it: {}", absent(plan).1);
    }
    say(out, &line)
}

/// Writes `bytes` to `out`, unless a signal came: then says so and
/// returns false.
fn write(out: &Output, bytes: &[u8], cancel: Cancel) -> Result<bool> {
    let written = cancel
        .check()
        .map_err(anyhow::Error::from)
        .and_then(|()| out.write_result(bytes, cancel));
    match written {
        Err(e) if e.is::<interrupt::Interrupted>() => {
            crate::noteln!("interrupted: nothing written");
            Ok(false)
        }
        written => written.map(|()| true),
    }
}

/// The closing line: on standard error where the output is standard
/// output.
fn say(out: &Output, line: &str) -> Result<ExitCode> {
    match out.is_stdout() {
        true => crate::noteln!("{line}"),
        false => crate::outln!("{line}")?,
    }
    Ok(ExitCode::SUCCESS)
}

/// What is missing: `parts 3/4 and 4/4 are missing (samples 6..12 of
/// 0..12)`, or the samples where they are not whole parts.
fn missing(plan: &MergePlan) -> String {
    match absent(plan) {
        (Some(parts), samples) => format!("{parts} missing ({samples})"),
        (None, samples) => format!("{samples} are missing"),
    }
}

/// The missing parts (`parts 3/4 and 4/4 are`) where they are whole
/// parts, and the missing samples (`samples 6..12 of 0..12`).
fn absent(plan: &MergePlan) -> (Option<String>, String) {
    let samples = format!(
        "samples {} of 0..{}",
        ranges_text(&plan.missing),
        plan.total
    );
    let parts = plan.missing_parts().map(|(n, ks)| {
        let names: Vec<String> = ks.iter().map(|k| format!("{k}/{n}")).collect();
        match names.len() {
            1 => format!("part {} is", names[0]),
            _ => format!("parts {} are", listed(&names)),
        }
    });
    (parts, samples)
}

/// `a`, `a and b`, `a, b and c`.
fn listed(w: &[String]) -> String {
    match w {
        [] => String::new(),
        [one] => one.clone(),
        [init @ .., last] => format!("{} and {last}", init.join(", ")),
    }
}

/// The commands that render what is missing, from the options the parts
/// recorded: one a line.
fn to_render(plan: &MergePlan) -> String {
    let first = &plan.parts[0];
    let options = &first.1.meta.command;
    if options.is_empty() {
        return "the missing samples with the options the other parts were rendered with"
            .to_string();
    }
    let commands: Vec<String> = match plan.missing_parts() {
        Some((n, ks)) => ks
            .iter()
            .map(|&k| {
                let out = part_name(plan, k);
                command(options, &["--part", &format!("{k}/{n}")], &out)
            })
            .collect(),
        None => {
            // --samples takes no --spp.
            let mut kept = Vec::new();
            let mut words = options.iter();
            while let Some(w) = words.next() {
                match w.as_str() {
                    "--spp" => {
                        words.next();
                    }
                    w if w.starts_with("--spp=") => {}
                    _ => kept.push(w.clone()),
                }
            }
            plan.missing
                .iter()
                .map(|m| {
                    let out = first
                        .0
                        .with_file_name(format!("samples-{}-{}.exr", m.start, m.end));
                    command(
                        &kept,
                        &["--samples", &format!("{}..{}", m.start, m.end)],
                        &out,
                    )
                })
                .collect()
        }
    };
    let them = if commands.len() == 1 { "it" } else { "them" };
    format!("{them} with\n  {}", commands.join("\n  "))
}

/// `rayterm render OPTIONS EXTRA -o OUT`, quoted for a POSIX shell.
fn command(options: &[String], extra: &[&str], out: &Path) -> String {
    let mut words = vec!["rayterm".to_string(), "render".to_string()];
    words.extend(options.iter().cloned());
    words.extend(extra.iter().map(|w| w.to_string()));
    words.extend(["-o".to_string(), out.display().to_string()]);
    words
        .iter()
        .map(|w| shell_word(w))
        .collect::<Vec<_>>()
        .join(" ")
}

/// The file part K/N goes to: a present part's name with its own K made
/// this one where the name holds it once (`part-2.exr` for `part-3.exr`),
/// else `part-K.exr` beside it.
fn part_name(plan: &MergePlan, k: u32) -> PathBuf {
    let (path, h) = plan
        .parts
        .iter()
        .find(|(_, h)| h.meta.part.is_some())
        .unwrap_or(&plan.parts[0]);
    let fallback = path.with_file_name(format!("part-{k}.exr"));
    let (Some((own, _)), Some(name)) = (h.meta.part, path.file_name().and_then(|n| n.to_str()))
    else {
        return fallback;
    };
    // The runs of digits in the name: exactly one must be K.
    let mut runs = Vec::new();
    let mut at = None;
    for (i, c) in name.char_indices().chain([(name.len(), ' ')]) {
        match (c.is_ascii_digit(), at) {
            (true, None) => at = Some(i),
            (false, Some(a)) => {
                runs.push(a..i);
                at = None;
            }
            _ => {}
        }
    }
    let own = own.to_string();
    let hits: Vec<_> = runs.iter().filter(|r| name[(*r).clone()] == own).collect();
    match hits.as_slice() {
        [r] => path.with_file_name(format!("{}{k}{}", &name[..r.start], &name[r.end..])),
        _ => fallback,
    }
}

/// `w` as one word for a POSIX shell: as it is where it holds nothing a
/// shell reads, else in single quotes.
fn shell_word(w: &str) -> String {
    let plain = !w.is_empty()
        && w.chars()
            .all(|c| c.is_ascii_alphanumeric() || "_-./:,=+@%".contains(c));
    match plain {
        true => w.to_string(),
        false => format!("'{}'", w.replace('\'', "'\\''")),
    }
}

/// `merge --check SCENE`: refuses parts not rendered from the scene as it
/// loads here, with the options the parts recorded, saying which of its
/// files differ where the parts recorded them.
fn check(spec: &str, plan: &MergePlan) -> Result<()> {
    let (path, first) = &plan.parts[0];
    let there = &first.meta;
    let recorded = options(&there.command);
    if recorded.is_none() {
        crate::noteln!(
            "note: {} records no render options: {spec} is checked with the defaults",
            words::path(path)
        );
    }
    let request = SceneRequest {
        spec: spec.to_string(),
        check_film: false,
        ..recorded.unwrap_or_else(|| SceneRequest::new(spec))
    };
    let s = super::open_request(&request)?;
    let here = Meta::of(&s, None);
    if here.hash == there.hash {
        crate::noteln!(
            "check: the parts were rendered from {} as it loads here (content hash {:016x})",
            words::quoted(spec),
            here.hash
        );
        return Ok(());
    }
    let why = match (&there.inputs, &here.inputs) {
        (Some(theirs), Some(ours)) => {
            let mut why = Vec::new();
            for t in theirs {
                let name = t.path.display().to_string();
                match ours
                    .iter()
                    .find(|o| o.path == t.path)
                    .or_else(|| same_name(ours, &t.path))
                {
                    Some(o) if o.crc != t.crc => why.push(format!(
                        "{}: differs (CRC-32 {:08x} in the parts, {:08x} here)",
                        words::quoted(&name),
                        t.crc,
                        o.crc
                    )),
                    Some(_) => {}
                    None => why.push(format!(
                        "{}: read by the parts, not here",
                        words::quoted(&name)
                    )),
                }
            }
            for o in ours {
                let found =
                    theirs.iter().any(|t| t.path == o.path) || same_name(theirs, &o.path).is_some();
                if !found {
                    why.push(format!(
                        "{}: read here, not by the parts (missing where they were rendered?)",
                        words::path(&o.path)
                    ));
                }
            }
            if why.is_empty() {
                why.push(match there.version == here.version {
                    true => "no file it reads differs: the scene or its options do".to_string(),
                    false => format!(
                        "the parts are of rayterm {}, this is {}",
                        there.version, here.version
                    ),
                });
            }
            why
        }
        _ => {
            let mut why =
                vec!["the parts record no list of the files they read; here it reads:".to_string()];
            why.extend(
                here.inputs
                    .iter()
                    .flatten()
                    .map(|i| format!("  {}", words::path(&i.path))),
            );
            why
        }
    };
    bail!(
        "{}: not rendered from {} as it loads here (content hash {:016x} in the parts, {:016x} here):\n  {}",
        words::path(path),
        words::quoted(spec),
        there.hash,
        here.hash,
        why.join("\n  ")
    )
}

/// The input of `list` with the file name of `path`, where only one has it.
fn same_name<'a>(
    list: &'a [crate::scene::load::source::InputFile],
    path: &Path,
) -> Option<&'a crate::scene::load::source::InputFile> {
    let name = path.file_name()?;
    let mut hits = list.iter().filter(|i| i.path.file_name() == Some(name));
    match (hits.next(), hits.next()) {
        (Some(one), None) => Some(one),
        _ => None,
    }
}

/// The scene request a part's recorded options make.
fn options(words: &[String]) -> Option<SceneRequest> {
    if words.is_empty() {
        return None;
    }
    let mut args = vec!["rayterm".to_string(), "render".to_string()];
    args.extend(words.iter().cloned());
    args.extend(["-o".into(), "check.exr".into()]);
    match Cli::try_parse_from(args).ok()?.command? {
        Command::Render(r) => Some(r.scene.request()),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn words_a_shell_would_read_are_quoted() {
        assert_eq!(shell_word("--size"), "--size");
        assert_eq!(shell_word("my scene.toml"), "'my scene.toml'");
        assert_eq!(shell_word("it's"), "'it'\\''s'");
        assert_eq!(shell_word(""), "''");
    }
}
