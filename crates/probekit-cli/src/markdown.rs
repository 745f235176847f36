//! `docs/cli.md`, written from the command-line definition itself, so the
//! page cannot drift from `--help` (a test compares them).

use clap::{Arg, Command};
use std::fmt::Write;

/// The reference page of every subcommand: usage, then its arguments
/// grouped under their help headings.
pub fn cli_markdown(cmd: &Command) -> String {
    let mut out = String::new();
    let _ = writeln!(out, "# Command-line reference\n");
    let _ = writeln!(
        out,
        "Generated from `probekit --help` by `probekit markdown-help > docs/cli.md` (a test \
         checks it is current). Every command prints one line `error: FILE: problem` and exits \
         with 1 on bad input; long commands show a progress bar on a terminal and a line per \
         phase in a pipe; `--json` prints one JSON object.\n"
    );
    let _ = writeln!(out, "| command | what |\n|---|---|");
    for sub in visible(cmd) {
        let _ = writeln!(
            out,
            "| [`{}`](#{}) | {} |",
            sub.get_name(),
            sub.get_name(),
            one_line(sub.get_about().map(|s| s.to_string()).unwrap_or_default())
        );
    }
    for sub in visible(cmd) {
        section(&mut out, sub);
    }
    out
}

/// The subcommands shown in help.
fn visible(cmd: &Command) -> impl Iterator<Item = &Command> {
    cmd.get_subcommands()
        .filter(|s| !s.is_hide_set() && s.get_name() != "help")
}

/// A help text on one line.
fn one_line(s: String) -> String {
    s.split_whitespace().collect::<Vec<_>>().join(" ")
}

fn section(out: &mut String, sub: &Command) {
    let name = sub.get_name();
    let _ = writeln!(out, "\n## {name}\n");
    let about = sub
        .get_long_about()
        .or(sub.get_about())
        .map(|s| s.to_string())
        .unwrap_or_default();
    let _ = writeln!(out, "{}\n", about.trim());
    let mut usage = sub.clone().bin_name(format!("probekit {name}"));
    let _ = writeln!(
        out,
        "```text\n{}\n```\n",
        usage
            .render_usage()
            .to_string()
            .trim_start_matches("Usage: ")
    );
    let args: Vec<&Arg> = sub
        .get_arguments()
        .filter(|a| !a.is_hide_set() && a.get_id() != "help")
        .collect();
    let mut headings: Vec<Option<&str>> = Vec::new();
    for a in &args {
        let h = a.get_help_heading();
        if !headings.contains(&h) {
            headings.push(h);
        }
    }
    for h in headings {
        let title = match h {
            Some(t) => t.to_string(),
            None => "Arguments".to_string(),
        };
        let _ = writeln!(out, "**{title}**\n");
        for a in args.iter().filter(|a| a.get_help_heading() == h) {
            let _ = writeln!(out, "- {}: {}", spell(a), describe(a));
        }
        let _ = writeln!(out);
    }
}

/// `--budget <N>`, `-o, --output <FILE>`, `<SCENE>`.
fn spell(a: &Arg) -> String {
    let value = a
        .get_value_names()
        .map(|v| {
            v.iter()
                .map(|n| format!("<{n}>"))
                .collect::<Vec<_>>()
                .join(" ")
        })
        .unwrap_or_default();
    let takes = a.get_num_args().is_some_and(|n| n.takes_values());
    let mut s = match (a.get_short(), a.get_long()) {
        (Some(c), Some(l)) => format!("`-{c}, --{l}"),
        (None, Some(l)) => format!("`--{l}"),
        (Some(c), None) => format!("`-{c}"),
        (None, None) => {
            return format!(
                "`{}`",
                if value.is_empty() {
                    a.get_id().to_string()
                } else {
                    value
                }
            )
        }
    };
    if takes && !value.is_empty() {
        s.push(' ');
        s.push_str(&value);
    }
    s.push('`');
    s
}

/// The help text, the choices of an enum and the default.
fn describe(a: &Arg) -> String {
    let mut d = one_line(
        a.get_long_help()
            .or(a.get_help())
            .map(|s| s.to_string())
            .unwrap_or_default(),
    );
    let choices: Vec<String> = a
        .get_possible_values()
        .iter()
        .filter(|v| !v.is_hide_set())
        .map(|v| format!("`{}`", v.get_name()))
        .collect();
    if !choices.is_empty() {
        let _ = write!(d, " Choices: {}.", choices.join(", "));
    }
    let defaults: Vec<String> = a
        .get_default_values()
        .iter()
        .map(|v| v.to_string_lossy().into_owned())
        .collect();
    if !defaults.is_empty() {
        let _ = write!(d, " Default: `{}`.", defaults.join(","));
    }
    d
}
