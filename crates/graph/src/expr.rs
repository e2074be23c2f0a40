//! Frame expressions: a number param written as a string holds an expression of the frame
//! number (`"0.25 * frame"`, `"$F"`, `"math::sin(frame / 12) * 2"`), evaluated by the
//! `evalexpr` crate. `frame`, `$F` and `$FF` (Houdini's names) are the frame number;
//! number literals are real numbers (`1/2` is 0.5, not integer division). Outside a
//! sequence the frame is [`DEFAULT_FRAME`]; a sequence (`render --frames`, the session's
//! `set_frame`, the editor's frame control) puts each frame's number in
//! ([`substitute`]).

use evalexpr::{
    ContextWithMutableVariables, DefaultNumericTypes, HashMapContext, Value,
    eval_number_with_context,
};

/// The frame an expression sees outside a sequence (Blender's and Houdini's first frame).
pub const DEFAULT_FRAME: i64 = 1;

/// Whether the expression `text` reads the frame number.
pub fn uses_frame(text: &str) -> bool {
    tokens(text).iter().any(|t| matches!(t, Token::Frame))
}

/// `text` with the frame number `frame` written in for `frame`, `$F` and `$FF`: the same
/// expression at that frame, which evaluates to the same value at any frame.
pub fn substitute(text: &str, frame: i64) -> String {
    tokens(text)
        .into_iter()
        .map(|t| match t {
            Token::Frame => format!("({frame})"),
            Token::Other(s) => s,
        })
        .collect()
}

/// The value of the expression `text` at frame `frame`.
///
/// # Errors
/// A syntax error, an unknown name or function, or a result that is not a finite number:
/// the message quotes the expression.
pub fn evaluate(text: &str, frame: i64) -> Result<f64, String> {
    let mut context = HashMapContext::<DefaultNumericTypes>::new();
    #[expect(clippy::cast_precision_loss, reason = "frame numbers are small")]
    let value = Value::Float(frame as f64);
    context
        .set_value("frame".into(), value)
        .map_err(|e| e.to_string())?;
    let prepared = prepare(text);
    let v = eval_number_with_context(&prepared, &context).map_err(|e| {
        format!(
            "the frame expression {text:?} does not evaluate: {e} (write numbers, `frame` or \
             `$F`, + - * / ^ %, and functions such as min, max, floor, math::sin)"
        )
    })?;
    if v.is_finite() {
        Ok(v)
    } else {
        Err(format!(
            "the frame expression {text:?} gives {v} at frame {frame}"
        ))
    }
}

/// `text` as evalexpr reads it: the frame names as `frame`, integer literals as reals.
fn prepare(text: &str) -> String {
    tokens(text)
        .into_iter()
        .map(|t| match t {
            Token::Frame => "frame".to_owned(),
            Token::Other(s) if is_integer_literal(&s) => format!("{s}.0"),
            Token::Other(s) => s,
        })
        .collect()
}

fn is_integer_literal(s: &str) -> bool {
    !s.is_empty() && s.bytes().all(|b| b.is_ascii_digit())
}

#[derive(Debug, PartialEq)]
enum Token {
    /// `frame`, `$F` or `$FF`.
    Frame,
    /// Anything else, as written: a name, a number, an operator, spaces.
    Other(String),
}

/// Splits `text` into names (letters, digits, `_`, `::`; a leading `$`), numbers (digits
/// and `.`, an exponent) and single other characters.
fn tokens(text: &str) -> Vec<Token> {
    let chars: Vec<char> = text.chars().collect();
    let mut out = Vec::new();
    let mut i = 0;
    while i < chars.len() {
        let c = chars[i];
        let start = i;
        if c.is_ascii_alphabetic() || c == '_' || c == '$' {
            i += 1;
            while i < chars.len()
                && (chars[i].is_ascii_alphanumeric()
                    || chars[i] == '_'
                    || (chars[i] == ':' && chars.get(i + 1) == Some(&':')))
            {
                i += if chars[i] == ':' { 2 } else { 1 };
            }
        } else if c.is_ascii_digit() || c == '.' {
            i += 1;
            while i < chars.len() && (chars[i].is_ascii_digit() || chars[i] == '.') {
                i += 1;
            }
            // An exponent: 1e-3, 2.5E+4.
            if i < chars.len() && matches!(chars[i], 'e' | 'E') {
                let mut j = i + 1;
                if j < chars.len() && matches!(chars[j], '+' | '-') {
                    j += 1;
                }
                if j < chars.len() && chars[j].is_ascii_digit() {
                    i = j;
                    while i < chars.len() && chars[i].is_ascii_digit() {
                        i += 1;
                    }
                }
            }
        } else {
            i += 1;
        }
        let word: String = chars[start..i].iter().collect();
        out.push(if matches!(word.as_str(), "frame" | "$F" | "$FF") {
            Token::Frame
        } else {
            Token::Other(word)
        });
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn expressions_of_the_frame_evaluate() {
        assert_eq!(evaluate("frame", 7), Ok(7.0));
        assert_eq!(evaluate("$F * 2", 7), Ok(14.0));
        assert_eq!(evaluate("$FF / 2", 7), Ok(3.5));
        // Integer literals are reals: no integer division.
        assert_eq!(evaluate("1/2", 7), Ok(0.5));
        assert_eq!(evaluate("frame / 10", 7), Ok(0.7));
        assert_eq!(evaluate("1e-3 * frame", 2), Ok(0.002));
        assert_eq!(evaluate("max(frame - 10, 0)", 7), Ok(0.0));
        assert_eq!(evaluate("floor(frame / 2)", 7), Ok(3.0));
        assert!((evaluate("math::sin(frame)", 7).unwrap() - 7.0_f64.sin()).abs() < 1e-12);
        // A name that merely contains "frame" is not the frame.
        assert!(!uses_frame("frames + 1"));
        assert!(uses_frame("0.5*$F"));
        assert!(!uses_frame("2 * 3"));
    }

    #[test]
    fn a_bad_expression_is_one_error_quoting_it() {
        let e = evaluate("frame +", 1).unwrap_err();
        assert!(e.contains("\"frame +\""), "{e}");
        let e = evaluate("frme * 2", 1).unwrap_err();
        assert!(e.contains("frme"), "{e}");
        let e = evaluate("1 / (frame - 1)", 1).unwrap_err();
        assert!(e.contains("inf"), "{e}");
    }

    #[test]
    fn substituting_the_frame_keeps_the_value() {
        let s = substitute("0.25 * $F + frame", 12);
        assert_eq!(s, "0.25 * (12) + (12)");
        assert_eq!(evaluate(&s, 1), evaluate("0.25 * $F + frame", 12));
        // A negative frame.
        assert_eq!(evaluate(&substitute("frame * 2", -3), 1), Ok(-6.0));
    }
}
