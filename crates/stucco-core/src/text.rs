//! Places in text files, for errors that name a line and a column.

/// 1-based line and column of byte `offset` in `text` (offsets past the
/// end count as the end).
pub fn line_column(text: &str, offset: usize) -> (usize, usize) {
    let before = &text[..offset.min(text.len())];
    let line = before.matches('\n').count() + 1;
    let column = before.len() - before.rfind('\n').map_or(0, |i| i + 1) + 1;
    (line, column)
}

/// A number in a TOML file that is no number: TOML reads `nan` and `inf`,
/// and every comparison a range check makes with `nan` is false.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct NonFinite {
    /// Its field, named as checks name fields: `room[2].corners`,
    /// `tours.hall.points`, `seconds`.
    pub field: String,
    /// 1-based line of the number.
    pub line: usize,
    /// 1-based column of the number.
    pub column: usize,
}

/// The first number in the TOML `text` (first in the file) that is not
/// finite; `None` when there is none or the text is no TOML (its
/// deserializer tells that better).
pub fn first_non_finite(text: &str) -> Option<NonFinite> {
    let root = toml::de::DeTable::parse(text).ok()?;
    let mut found: Option<(usize, String)> = None;
    for (key, value) in root.get_ref() {
        non_finite_in(value, key.get_ref(), &mut found);
    }
    found.map(|(offset, field)| {
        let (line, column) = line_column(text, offset);
        NonFinite {
            field,
            line,
            column,
        }
    })
}

/// Keeps in `found` the earliest non-finite number under `value`.
fn non_finite_in(
    value: &toml::Spanned<toml::de::DeValue<'_>>,
    field: &str,
    found: &mut Option<(usize, String)>,
) {
    use toml::de::DeValue;
    let start = value.span().start;
    match value.get_ref() {
        DeValue::Float(x) => {
            let finite = x.as_str().parse::<f64>().is_ok_and(f64::is_finite);
            if !finite && found.as_ref().is_none_or(|(at, _)| start < *at) {
                *found = Some((start, field.to_owned()));
            }
        }
        DeValue::Table(table) => {
            for (key, value) in table {
                non_finite_in(value, &format!("{field}.{}", key.get_ref()), found);
            }
        }
        DeValue::Array(items) => {
            for (i, item) in items.iter().enumerate() {
                match item.get_ref() {
                    DeValue::Table(_) => non_finite_in(item, &format!("{field}[{i}]"), found),
                    _ => non_finite_in(item, field, found),
                }
            }
        }
        _ => {}
    }
}

#[cfg(test)]
#[allow(clippy::expect_used)]
mod tests {
    use super::*;

    #[test]
    fn lines_and_columns_count_from_one() {
        let text = "a = 1\nbb = 2\n";
        assert_eq!(line_column(text, 0), (1, 1));
        assert_eq!(line_column(text, 6), (2, 1));
        assert_eq!(line_column(text, 9), (2, 4));
        assert_eq!(line_column(text, 1000), (3, 1));
    }

    #[test]
    fn the_first_number_that_is_no_number_is_named_at_its_place() {
        let text = "seconds = 10.0\n\
                    [[room]]\ncorners = [[0.0, 0.0], [1.0, 0.0]]\n\
                    [[room]]\ncorners = [[0.0, 0.0], [nan, 0.0]]\n\
                    [tours.hall]\nspeed = -inf\n";
        let bad = first_non_finite(text).expect("nan and -inf are found");
        assert_eq!(bad.field, "room[1].corners");
        assert_eq!((bad.line, bad.column), (5, 25));

        let later = text.replace("nan", "2.0");
        let bad = first_non_finite(&later).expect("-inf is found");
        assert_eq!(bad.field, "tours.hall.speed");
        assert_eq!((bad.line, bad.column), (7, 9));

        assert_eq!(first_non_finite(&later.replace("-inf", "1e3")), None);
        assert_eq!(first_non_finite("not = [toml"), None);
    }
}
