//! The Linux programs' command line (fcc-bridge, fcc-mission, fcc-sitl, fcc-wire-fault): clap's
//! parse, with a bad command line reported as ONE line, `<program>: <reason> (see --help)`, and
//! exit status 2, as every other bad input; `--help` and `--version` print and exit 0.

use std::ffi::OsString;

/// Parse `args` (the program's name first) as `T`; on `Err`, the process's exit status: 0 after
/// `--help`/`--version` were printed, 2 after the one-line error was.
pub fn parse<T, I, S>(program: &str, args: I) -> Result<T, u8>
where
    T: clap::Parser,
    I: IntoIterator<Item = S>,
    S: Into<OsString> + Clone,
{
    T::try_parse_from(args).map_err(|e| report(program, e))
}

/// As [`parse`], with `after_help` appended to `--help` (text generated at run time, e.g. from a
/// parameter table).
pub fn parse_with_help<T, I, S>(program: &str, args: I, after_help: String) -> Result<T, u8>
where
    T: clap::Parser,
    I: IntoIterator<Item = S>,
    S: Into<OsString> + Clone,
{
    T::command()
        .after_help(after_help)
        .try_get_matches_from(args)
        .and_then(|m| T::from_arg_matches(&m))
        .map_err(|e| report(program, e))
}

/// Prints clap's error (help/version as clap does, a real error as one line); the exit status.
fn report(program: &str, e: clap::Error) -> u8 {
    if !e.use_stderr() {
        let _ = e.print();
        return 0;
    }
    eprintln!("{program}: {} (see --help)", one_line(&e));
    2
}

/// clap's error as one line: its text up to the usage block, whitespace collapsed, without the
/// `error: ` prefix (clap's own text spans several lines).
pub fn one_line(e: &clap::Error) -> String {
    let text = e.to_string();
    text.split("\n\nUsage")
        .next()
        .unwrap_or("")
        .split_whitespace()
        .collect::<Vec<_>>()
        .join(" ")
        .trim_start_matches("error: ")
        .to_string()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(clap::Parser, Debug)]
    struct Args {
        #[arg(long)]
        rate_hz: f64,
    }

    #[test]
    fn a_bad_command_line_is_one_line_and_exit_2() {
        let e = <Args as clap::Parser>::try_parse_from(["p", "--rate-hz", "fast"]).unwrap_err();
        let line = one_line(&e);
        assert!(
            !line.contains('\n') && !line.starts_with("error:"),
            "{line}"
        );
        assert!(
            line.contains("--rate-hz") && line.contains("fast"),
            "{line}"
        );
        assert_eq!(
            parse::<Args, _, _>("p", ["p", "--rate-hz", "fast"]).unwrap_err(),
            2
        );
        assert_eq!(parse::<Args, _, _>("p", ["p", "--help"]).unwrap_err(), 0);
        assert_eq!(
            parse::<Args, _, _>("p", ["p", "--rate-hz", "2.5"])
                .unwrap()
                .rate_hz,
            2.5
        );
    }
}
