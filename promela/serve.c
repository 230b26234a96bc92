/* pan, and a server that runs pan on many scenarios in one process: compiled instead of pan.c alone.
 *
 * Without --serve this program is pan (every option, every output). With --serve it reads requests
 * on stdin, one per line, tab separated:
 *
 *     <work dir> TAB <time limit in ms> TAB <scenario> TAB <pan argument> [TAB <pan argument>...]
 *
 * and for each one forks a copy of itself that sets OVERTAKE_SCENARIO, changes into the work dir,
 * sends stdout and stderr to <work dir>/out.txt and runs pan's main with those arguments. The copy
 * starts from the server's pristine globals, so every search is pan's own from a fresh start,
 * without the exec, the dynamic linking and the interpreter's process set-up. A model may name a
 * hook, SERVE_PREPARE(scenario), that the server calls before each fork to read data the runs share
 * (the sound model's table, once per table: promela.sound); a run finds it read, or reads it
 * itself. The server answers each request with one line once the copy has ended: "exit N",
 * "signal N" or "timeout" (the copy was killed at the time limit), or "error <reason>". Both die
 * with their parent (PR_SET_PDEATHSIG).
 */
#define main pan_main
#include "pan.c"
#undef main

#include <errno.h>
#include <fcntl.h>
#include <sys/prctl.h>
#include <sys/time.h>
#include <sys/wait.h>
#include <unistd.h>

#define SERVE_MAX_LINE 65536
#define SERVE_MAX_ARGS 32

static volatile pid_t serve_child = 0;
static volatile sig_atomic_t serve_timed_out = 0;

static void serve_on_alarm(int signo)
{	(void) signo;
	if (serve_child > 0) { serve_timed_out = 1; kill(serve_child, SIGKILL); }
}

static void serve_reply(const char *text)
{	fputs(text, stdout);
	fputc('\n', stdout);
	fflush(stdout);
}

static int serve_run(char *dir, long limit_ms, char *scenario, int argc, char **argv)
{	struct itimerval timer;
	int status, out;
	pid_t pid;

#ifdef SERVE_PREPARE
	SERVE_PREPARE(scenario);
#endif
	fflush(NULL);
	pid = fork();
	if (pid < 0) { return -1; }
	if (pid == 0)
	{	prctl(PR_SET_PDEATHSIG, SIGKILL);
		signal(SIGALRM, SIG_DFL);
		signal(SIGINT, SIG_DFL);
		if (chdir(dir) != 0) { _exit(120); }
		out = open("out.txt", O_WRONLY | O_CREAT | O_TRUNC, 0644);
		if (out < 0) { _exit(121); }
		dup2(out, 1); dup2(out, 2); close(out);
		out = open("/dev/null", O_RDONLY);
		if (out >= 0) { dup2(out, 0); close(out); }
		if (setenv("OVERTAKE_SCENARIO", scenario, 1) != 0) { _exit(122); }
		exit(pan_main(argc, argv));
	}
	serve_child = pid;
	serve_timed_out = 0;
	memset(&timer, 0, sizeof(timer));
	timer.it_value.tv_sec = limit_ms / 1000;
	timer.it_value.tv_usec = (limit_ms % 1000) * 1000;
	setitimer(ITIMER_REAL, &timer, NULL);
	while (waitpid(pid, &status, 0) < 0)
	{	if (errno != EINTR) { status = -1; break; }
	}
	memset(&timer, 0, sizeof(timer));
	setitimer(ITIMER_REAL, &timer, NULL);
	serve_child = 0;
	if (serve_timed_out) { serve_reply("timeout"); return 0; }
	if (status == -1) { serve_reply("error waitpid failed"); return 0; }
	if (WIFEXITED(status)) { printf("exit %d\n", WEXITSTATUS(status)); fflush(stdout); return 0; }
	printf("signal %d\n", WIFSIGNALED(status) ? WTERMSIG(status) : 0);
	fflush(stdout);
	return 0;
}

static int serve(char *self)
{	static char line[SERVE_MAX_LINE];
	char *fields[SERVE_MAX_ARGS + 3], *at, *tab;
	struct sigaction alarm_action;
	int n;

	prctl(PR_SET_PDEATHSIG, SIGKILL);
	signal(SIGINT, SIG_IGN);  /* the parent decides what Ctrl-C means; this server ends with it */
	memset(&alarm_action, 0, sizeof(alarm_action));
	alarm_action.sa_handler = serve_on_alarm;
	sigaction(SIGALRM, &alarm_action, NULL);  /* no SA_RESTART: waitpid returns on the alarm */
	serve_reply("ready");
	while (fgets(line, sizeof(line), stdin) != NULL)
	{	at = line;
		at[strcspn(at, "\n")] = '\0';
		for (n = 0; n < SERVE_MAX_ARGS + 3; n++)
		{	fields[n] = at;
			tab = strchr(at, '\t');
			if (tab == NULL) { n++; break; }
			*tab = '\0';
			at = tab + 1;
		}
		if (n < 4 || strchr(at, '\t') != NULL) { serve_reply("error malformed request"); continue; }
		{	char *args[SERVE_MAX_ARGS + 2];
			int k, count = 0;
			args[count++] = self;
			for (k = 3; k < n; k++) { args[count++] = fields[k]; }
			args[count] = NULL;
			if (serve_run(fields[0], strtol(fields[1], NULL, 10), fields[2], count, args) != 0)
			{	serve_reply("error fork failed");
			}
		}
	}
	return 0;
}

int
main(int argc, char *argv[])
{	if (argc == 2 && strcmp(argv[1], "--serve") == 0) { return serve(argv[0]); }
	return pan_main(argc, argv);
}
