//! Before the session: spoken questions with typed answers (the server's address, the join code), each
//! typed character said back, and every failure said with what to do next — so a blind player joins or
//! hosts with the keyboard alone.
//!
//! You need this module to change what is asked or said before the game starts. A [`Prompter`] owns the
//! audio engine and the speaker until the game takes them over, so everything said before and during
//! the game lands in one recording (`--audio memory --wav FILE`).

use std::net::SocketAddr;
use std::time::{Duration, Instant};

use heist_client::JoinError;
use heist_shared::protocol::join::JoinRefusal;

use crate::audio::AudioEngine;
use crate::client::PhantomSettings;
use crate::error::ClientError;
use crate::speech::Speaker;

/// The port a typed address without one gets.
pub const DEFAULT_PORT: u16 = 5757;

/// What to do after a failed join.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Next {
    /// Ask for the address again.
    Address,
    /// Ask for the code again.
    Code,
    /// Wait this many seconds, then ask for the code again.
    Wait(u32),
    /// Nothing more can be tried from here.
    Stop,
}

/// A failed join as the player hears it: what happened and what to do next, and what the prompt asks next.
pub fn advice(e: &JoinError) -> (String, Next) {
    use JoinRefusal as R;
    match e {
        JoinError::Unreachable { addr, .. } => (
            format!(
                "Nobody answers at {addr}. Check the address with your partner, and that the host's game is running."
            ),
            Next::Address,
        ),
        JoinError::BadCode(why) => (
            format!(
                "That is not a join code: {why}. A code looks like room, dash, four characters, dash, four characters."
            ),
            Next::Code,
        ),
        JoinError::Refused(r) => match r {
            R::WrongCode => ("The host says that code is wrong. Check it with your partner.".to_owned(), Next::Code),
            R::CodeExpired => ("That code has expired. Ask your partner for a new one.".to_owned(), Next::Code),
            R::RoleTaken(role) => (
                format!("Someone already plays {role} in that session. Ask your partner for the right code."),
                Next::Code,
            ),
            R::SeatHeld { role, for_s } => (
                format!(
                    "The {role} seat is kept for the player who dropped from it, for {for_s} seconds more. \
If that was you, run the same command again to take it back."
                ),
                Next::Stop,
            ),
            R::TooManyWrongCodes { retry_after_s }
            | R::Busy { retry_after_s }
            | R::TooManySessions { retry_after_s } => (
                format!("The host is not taking codes from here for {retry_after_s} seconds. Wait, then try again."),
                Next::Wait(*retry_after_s),
            ),
            R::Full { max } => (
                format!("That server hosts {max} sessions, its most. Try again later, or host your own heist."),
                Next::Stop,
            ),
            R::Version { .. } => (format!("{r}. Then join again."), Next::Stop),
            other => (format!("The host refused: {other}."), Next::Stop),
        },
        other => (format!("Joining failed: {other}."), Next::Stop),
    }
}

/// How a typed character is said back.
pub fn char_name(c: char) -> String {
    match c {
        '.' => "dot".into(),
        ':' => "colon".into(),
        '-' => "dash".into(),
        ' ' => "space".into(),
        '/' => "slash".into(),
        c if c.is_ascii_alphabetic() => c.to_ascii_uppercase().to_string(),
        c => c.to_string(),
    }
}

/// A typed address: `HOST:PORT`, or an IP address alone (port [`DEFAULT_PORT`]).
pub fn parse_address(text: &str) -> Result<SocketAddr, String> {
    let text = text.trim();
    if let Ok(a) = text.parse::<SocketAddr>() {
        return Ok(a);
    }
    if let Ok(ip) = text.parse::<std::net::IpAddr>() {
        return Ok(SocketAddr::new(ip, DEFAULT_PORT));
    }
    use std::net::ToSocketAddrs as _;
    let with_port = if text.contains(':') { text.to_owned() } else { format!("{text}:{DEFAULT_PORT}") };
    with_port
        .to_socket_addrs()
        .ok()
        .and_then(|mut a| a.next())
        .ok_or_else(|| format!("{text} is not an address a computer can be reached at"))
}

/// Sets a terminal on stdin to hand over each key as it is typed (no line editing, no echo: the
/// prompt echoes itself) and restores it when dropped; does nothing when stdin is not a terminal.
struct CharByChar {
    saved: Option<libc::termios>,
}

impl CharByChar {
    fn new() -> Self {
        // SAFETY: isatty, tcgetattr and tcsetattr only read and write the termios struct given, on fd 0.
        unsafe {
            if libc::isatty(0) != 1 {
                return Self { saved: None };
            }
            let mut t: libc::termios = std::mem::zeroed();
            if libc::tcgetattr(0, &mut t) != 0 {
                return Self { saved: None };
            }
            let saved = t;
            t.c_lflag &= !(libc::ICANON | libc::ECHO);
            t.c_cc[libc::VMIN] = 1;
            t.c_cc[libc::VTIME] = 0;
            libc::tcsetattr(0, libc::TCSANOW, &t);
            Self { saved: Some(saved) }
        }
    }

    fn on_terminal(&self) -> bool {
        self.saved.is_some()
    }
}

impl Drop for CharByChar {
    fn drop(&mut self) {
        if let Some(t) = self.saved {
            // SAFETY: restores the settings read in `new` on the same fd.
            unsafe {
                libc::tcsetattr(0, libc::TCSANOW, &t);
            }
        }
    }
}

/// The audio engine and speaker before the game, with spoken questions (see the module docs).
pub struct Prompter {
    /// The audio engine (handed to the game).
    pub audio: AudioEngine,
    /// The speaker (handed to the game).
    pub speaker: Speaker,
}

impl Prompter {
    /// Starts the audio engine and speaker with the player's settings, and says why the settings file
    /// was not used, if it was not (then the game does not say it again).
    pub fn new(settings: &mut PhantomSettings) -> Result<Self, ClientError> {
        let mut audio = AudioEngine::new(&settings.audio)?;
        let mut speaker = Speaker::new();
        crate::settings::plugin::apply(&settings.prefs.run, &mut speaker, &mut audio);
        if let Some(w) = settings.prefs.warning.take() {
            log::warn!("{w}");
            speaker.say(w);
        }
        Ok(Self { audio, speaker })
    }

    /// Says (and prints) `text`.
    pub fn say(&mut self, text: impl Into<String>) {
        self.speaker.say(text);
        self.pump();
    }

    /// Plays the speech that is ready, one line after the other.
    fn pump(&mut self) {
        for s in self.speaker.ready() {
            self.audio.speak(s);
        }
        self.audio.update();
    }

    /// Waits until everything said has been heard (at most `limit`).
    pub fn finish_speaking(&mut self, limit: Duration) {
        let deadline = Instant::now() + limit;
        while Instant::now() < deadline {
            self.pump();
            if self.speaker.pending() == 0 && !self.audio.is_speaking() {
                break;
            }
            std::thread::sleep(Duration::from_millis(20));
        }
    }

    /// Asks `question` and reads the typed answer, saying each character back (and the one a backspace
    /// deletes); `None` when input ended or the program was asked to stop.
    pub fn ask(&mut self, question: &str) -> Option<String> {
        use std::io::Write as _;
        self.say(question);
        let mode = CharByChar::new();
        let mut answer = String::new();
        let input = crate::terminal::stdin_bytes();
        loop {
            self.pump();
            if heist_client::signals::stop_requested() {
                return None;
            }
            let got = input.lock().unwrap_or_else(|p| p.into_inner()).recv_timeout(Duration::from_millis(20));
            let byte = match got {
                Ok(Some(b)) => b,
                Ok(None) | Err(std::sync::mpsc::RecvTimeoutError::Disconnected) => return None,
                Err(std::sync::mpsc::RecvTimeoutError::Timeout) => continue,
            };
            match byte {
                b'\n' | b'\r' => {
                    if mode.on_terminal() {
                        println!();
                    }
                    let answer = answer.trim().to_owned();
                    if answer.is_empty() {
                        self.say(format!("Nothing typed. {question}"));
                        continue;
                    }
                    return Some(answer);
                }
                0x7f | 0x08 => match answer.pop() {
                    Some(c) => {
                        self.speaker.speak_only(format!("deleted {}", char_name(c)));
                        if mode.on_terminal() {
                            print!("\u{8} \u{8}");
                            let _ = std::io::stdout().flush();
                        }
                    }
                    None => self.speaker.speak_only("nothing to delete"),
                },
                b if (b.is_ascii_graphic() || b == b' ') && answer.len() < 256 => {
                    let c = char::from(b);
                    answer.push(c);
                    self.speaker.speak_only(char_name(c));
                    if mode.on_terminal() {
                        print!("{c}");
                        let _ = std::io::stdout().flush();
                    }
                }
                _ => {}
            }
        }
    }

    /// Asks for the server's address until a usable one is typed.
    pub fn ask_address(&mut self) -> Option<SocketAddr> {
        let mut question = "Which server? Type its address and press Enter, for example 192.168.1.20 colon 5757. \
Backspace deletes."
            .to_owned();
        loop {
            let typed = self.ask(&question)?;
            match parse_address(&typed) {
                Ok(a) => {
                    self.say(format!("Server {a}."));
                    return Some(a);
                }
                Err(why) => question = format!("{why}. Type the address again."),
            }
        }
    }

    /// Asks for the join code until one of the right shape is typed.
    pub fn ask_code(&mut self) -> Option<String> {
        let mut question = "The join code? Type the code your partner gave you and press Enter.".to_owned();
        loop {
            let typed = self.ask(&question)?.to_ascii_uppercase();
            match heist_shared::protocol::join::room_of(&typed) {
                Ok(_) => {
                    self.say(format!("Code {}. Joining.", spell(&typed)));
                    return Some(typed);
                }
                Err(why) => question = format!("That is not a join code: {why}. Type the code again."),
            }
        }
    }

    /// Hands the audio engine and the speaker over (to the game).
    pub fn into_parts(mut self) -> (AudioEngine, Speaker) {
        self.pump();
        (self.audio, self.speaker)
    }
}

/// The NATO word (or the digit's name) for each character of a join code; the dash is a pause.
pub fn spell(code: &str) -> String {
    const NATO: [&str; 26] = [
        "alfa", "bravo", "charlie", "delta", "echo", "foxtrot", "golf", "hotel", "india", "juliett", "kilo", "lima",
        "mike", "november", "oscar", "papa", "quebec", "romeo", "sierra", "tango", "uniform", "victor", "whiskey",
        "x-ray", "yankee", "zulu",
    ];
    const DIGITS: [&str; 10] = ["zero", "one", "two", "three", "four", "five", "six", "seven", "eight", "nine"];
    let words: Vec<&str> = code
        .chars()
        .filter_map(|c| match c.to_ascii_uppercase() {
            c @ 'A'..='Z' => Some(NATO[usize::from(c as u8 - b'A')]),
            c @ '0'..='9' => Some(DIGITS[usize::from(c as u8 - b'0')]),
            '-' => Some("then"),
            _ => None,
        })
        .collect();
    words.join(", ")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_typed_address_may_leave_out_the_port() {
        assert_eq!(parse_address("10.0.0.7"), Ok("10.0.0.7:5757".parse().unwrap()));
        assert_eq!(parse_address(" 127.0.0.1:6000 "), Ok("127.0.0.1:6000".parse().unwrap()));
        assert!(parse_address("not an address!").unwrap_err().contains("not an address"));
    }

    #[test]
    fn typed_characters_are_named_as_a_listener_needs_them() {
        assert_eq!(char_name('k'), "K");
        assert_eq!(char_name('.'), "dot");
        assert_eq!(char_name(':'), "colon");
        assert_eq!(char_name('7'), "7");
    }

    #[test]
    fn every_refusal_says_what_to_do_next() {
        let wrong = advice(&JoinError::Refused(JoinRefusal::WrongCode));
        assert_eq!(wrong.1, Next::Code);
        assert!(wrong.0.contains("wrong") && wrong.0.contains("partner"), "{}", wrong.0);
        let unreachable = JoinError::Unreachable {
            addr: "127.0.0.1:1".parse().unwrap(),
            cause: std::io::Error::from(std::io::ErrorKind::ConnectionRefused),
        };
        let (said, next) = advice(&unreachable);
        assert!(said.contains("Nobody answers at 127.0.0.1:1"), "{said}");
        assert_eq!(next, Next::Address);
        let (said, next) = advice(&JoinError::Refused(JoinRefusal::Full { max: 32 }));
        assert!(said.contains("32 sessions") && said.contains("later"), "{said}");
        assert_eq!(next, Next::Stop);
        let wait = advice(&JoinError::Refused(JoinRefusal::TooManyWrongCodes { retry_after_s: 60 }));
        assert_eq!(wait.1, Next::Wait(60));
        assert!(
            advice(&JoinError::Refused(JoinRefusal::RoleTaken(heist_shared::protocol::Role::Phantom)))
                .0
                .contains("Someone already plays Phantom")
        );
    }

    #[test]
    fn a_code_is_spelled_in_the_nato_alphabet_with_digits_by_name() {
        assert_eq!(
            spell("K7QX-2M4P-R9TC"),
            "kilo, seven, quebec, x-ray, then, two, mike, four, papa, then, romeo, nine, tango, charlie"
        );
        assert_eq!(spell("ab"), "alfa, bravo");
    }
}
